#pragma once
// Shared pieces of the meltlab subcommands: exit codes, the progress line, error output.

#include <cstdio>
#include <string>

namespace meltlab::cli {

/// Exit codes of every subcommand.
enum ExitCode : int {
  kOk = 0,
  kInvalid = 1,      ///< the command ran and found the input invalid (mesh-info)
  kBadInput = 2,     ///< unreadable/invalid input or options: one-line error on stderr
  kInternal = 3,     ///< a broken invariant during a run (a bug worth a report)
  kInterrupted = 130,
};

/// A one-line progress display on stderr, drawn only if stderr is a terminal.
class ProgressLine {
 public:
  ProgressLine();
  ~ProgressLine();
  void update(long long done, long long total, const std::string& detail);
  void finish();
  bool active() const { return tty_; }

 private:
  bool tty_ = false;
  bool drawn_ = false;
};

}  // namespace meltlab::cli
