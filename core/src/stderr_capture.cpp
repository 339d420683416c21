#include <meltlab/core/stderr_capture.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace meltlab {

namespace {
std::mutex& capture_mutex() {
  static std::mutex mu;
  return mu;
}
}  // namespace

StderrCapture::StderrCapture() : lock_(capture_mutex()) {
  std::fflush(stderr);
  char name[] = "/tmp/meltlab-stderr-XXXXXX";
  capture_fd_ = ::mkstemp(name);
  if (capture_fd_ < 0) return;  // no capture possible: the library prints as it would anyway
  ::unlink(name);
  saved_fd_ = ::dup(STDERR_FILENO);
  if (saved_fd_ < 0 || ::dup2(capture_fd_, STDERR_FILENO) < 0) {
    if (saved_fd_ >= 0) ::close(saved_fd_);
    ::close(capture_fd_);
    saved_fd_ = capture_fd_ = -1;
  }
}

StderrCapture::~StderrCapture() {
  if (saved_fd_ < 0) return;
  std::fflush(stderr);
  ::dup2(saved_fd_, STDERR_FILENO);
  ::close(saved_fd_);
  ::close(capture_fd_);
}

std::string StderrCapture::text() const {
  if (capture_fd_ < 0) return {};
  std::fflush(stderr);
  std::string out;
  char buf[4096];
  for (off_t at = 0;;) {
    const ssize_t n = ::pread(capture_fd_, buf, sizeof buf, at);
    if (n <= 0) break;
    out.append(buf, static_cast<std::size_t>(n));
    at += n;
    if (out.size() > (1u << 16)) break;  // a message, not a log
  }
  return out;
}

}  // namespace meltlab
