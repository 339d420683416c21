#pragma once
// Libraries that print behind our back: libpng (through OpenImageIO) writes "libpng error: ..."
// straight to the process's standard error before OpenImageIO reports the same problem to us.
// meltlab's errors are one line, so such calls run inside a StderrCapture: file descriptor 2 is
// pointed at a temporary file for the duration, and what the library wrote can be read back
// (and folded into our one-line message) or dropped.
//
// File descriptor 2 belongs to the whole process: captures are serialised by a global mutex,
// and anything another thread writes to stderr meanwhile is captured too. Use it around short
// library calls that may fail on bad input, not around long computations.

#include <mutex>
#include <string>

namespace meltlab {

class StderrCapture {
 public:
  StderrCapture();
  ~StderrCapture();
  StderrCapture(const StderrCapture&) = delete;
  StderrCapture& operator=(const StderrCapture&) = delete;
  /// What was written to stderr since the capture began (may be empty).
  std::string text() const;

 private:
  std::unique_lock<std::mutex> lock_;
  int saved_fd_ = -1;
  int capture_fd_ = -1;
};

}  // namespace meltlab
