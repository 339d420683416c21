#include "cli_util.h"

#include <fmt/format.h>
#include <unistd.h>

namespace meltlab::cli {

namespace {
std::atomic<bool> g_interrupted{false};
extern "C" void on_interrupt(int) { g_interrupted.store(true); }
}  // namespace

InterruptScope::InterruptScope() {
  g_interrupted.store(false);
  previous_ = std::signal(SIGINT, on_interrupt);
}
InterruptScope::~InterruptScope() { std::signal(SIGINT, previous_); }
std::atomic<bool>* InterruptScope::flag() { return &g_interrupted; }

ProgressLine::ProgressLine() : tty_(::isatty(STDERR_FILENO) != 0) {}
ProgressLine::~ProgressLine() { finish(); }

void ProgressLine::update(long long done, long long total, const std::string& detail) {
  if (!tty_) return;
  constexpr int kWidth = 30;
  const double f = total > 0 ? static_cast<double>(done) / static_cast<double>(total) : 1.0;
  const int fill = static_cast<int>(f * kWidth);
  std::string bar(static_cast<std::size_t>(fill), '=');
  if (fill < kWidth) bar += '>';
  bar.resize(kWidth, ' ');
  std::fputs(fmt::format("\r[{}] {}/{} {}\x1b[K", bar, done, total, detail).c_str(), stderr);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressLine::finish() {
  if (tty_ && drawn_) {
    std::fputs("\n", stderr);
    drawn_ = false;
  }
}

}  // namespace meltlab::cli
