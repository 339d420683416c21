#pragma once
// Error types of meltlab. Every error is one line that names the input (file, option or
// field) and the problem, so the CLI can print `meltlab: <message>` and exit non-zero.

#include <stdexcept>
#include <string>

namespace meltlab {

/// Base of all meltlab errors.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
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

}  // namespace meltlab
