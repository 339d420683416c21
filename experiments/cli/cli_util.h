#pragma once
// Shared pieces of the meltlab subcommands: the progress line (exit codes: core/error.h).

#include <meltlab/core/error.h>

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

}  // namespace meltlab::cli
