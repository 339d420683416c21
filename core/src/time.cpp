#include <meltlab/core/time.h>

#include <cstdlib>
#include <ctime>

namespace meltlab {

std::string utc_timestamp_iso8601(std::chrono::system_clock::time_point t) {
  // floor, not to_time_t's implementation-defined rounding: a timestamp never lies in the future.
  const auto seconds = std::chrono::floor<std::chrono::seconds>(t);
  const std::time_t tt = static_cast<std::time_t>(seconds.time_since_epoch().count());
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  const std::size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return std::string(buf, n);
}

std::string utc_timestamp_iso8601_now() { return utc_timestamp_iso8601(std::chrono::system_clock::now()); }

double process_cpu_ms() {
  timespec ts{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

double thread_cpu_ms() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

std::array<double, 3> load_averages() {
  double l[3] = {-1, -1, -1};
  if (::getloadavg(l, 3) != 3) return {-1, -1, -1};
  return {l[0], l[1], l[2]};
}

}  // namespace meltlab
