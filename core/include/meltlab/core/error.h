#pragma once
// Error types and exit codes of meltlab. Every error is one line that names the input (file,
// option or field) and the problem, so the CLI can print `meltlab: <message>` and exit non-zero.

#include <stdexcept>
#include <string>

namespace meltlab {

/// Exit codes of every subcommand.
enum ExitCode : int {
  kExitOk = 0,
  kExitInvalid = 1,   ///< the command ran and found the input invalid (mesh-info)
  kExitBadInput = 2,  ///< unreadable/invalid input or options: one-line error on stderr
  kExitInternal = 3,  ///< a broken invariant during a run (a bug worth a report)
  kExitInterrupted = 130,
};

std::string one_line(const std::string& text);

/// Base of all meltlab errors. The message is made one line whatever it quotes (a key or value
/// of a hostile input may hold line breaks).
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(one_line(what)) {}
};

/// Bad user input: a missing/corrupt/invalid file, a bad number, a bad config value.
/// The message starts with the file (or option) it concerns: "bunny.off: open mesh: ...".
class InputError : public Error {
 public:
  using Error::Error;
};

/// A broken internal invariant detected at run time (e.g. a topology repair that did not
/// converge). Always a bug or a numerical breakdown worth a report, never bad input.
class InvariantError : public Error {
 public:
  using Error::Error;
};

/// Throws InputError(message) unless `ok`: the checks of options and values before a run
/// touches its output folder.
inline void require(bool ok, const std::string& message) {
  if (!ok) throw InputError(message);
}

/// Joins the lines of a library's message into one ("a; b"), without trailing blanks: meltlab's
/// errors are one line, whatever a library (or a hostile input echoed by it) puts in them.
inline std::string one_line(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    if (c == '\n') {
      if (!out.empty() && out.back() != ' ') out += "; ";
    } else if (c != '\r') {
      out += c;
    }
  }
  while (!out.empty() && (out.back() == ' ' || out.back() == ';')) out.pop_back();
  return out.empty() ? std::string("unknown error") : out;
}

}  // namespace meltlab
