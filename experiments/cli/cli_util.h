#pragma once
// Shared pieces of the meltlab subcommands: the progress line and the Ctrl-C scope (exit codes:
// core/error.h).

#include <meltlab/core/error.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <string>

namespace meltlab::cli {

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

/// While alive, SIGINT (Ctrl-C) sets `flag()` instead of killing the process, so a long run can
/// stop at its next step and still write what it finished; the previous handler comes back after.
/// One scope at a time (the flag is process-wide).
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
  std::atomic<bool>* flag();

 private:
  void (*previous_)(int) = SIG_DFL;
};

}  // namespace meltlab::cli
