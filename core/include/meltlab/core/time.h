#pragma once
// Wall-clock timestamps for records (run.json, fit.json, done.json, summary.json): one format
// everywhere, so records sort and compare as text; and the one stopwatch of timings.

#include <array>
#include <chrono>
#include <string>

namespace meltlab {

/// `t` as an ISO-8601 UTC timestamp to the second, "2026-11-25T12:04:44Z" (the fraction of
/// the second is dropped, not rounded). Thread-safe (gmtime_r).
std::string utc_timestamp_iso8601(std::chrono::system_clock::time_point t);

/// utc_timestamp_iso8601 of now.
std::string utc_timestamp_iso8601_now();

/// Milliseconds of wall-clock time since `t` (steady clock).
inline double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

/// CPU time of the process (every thread), ms: on a shared machine a single-threaded frame's CPU
/// time is steadier than its wall-clock time.
double process_cpu_ms();

/// CPU time of the calling thread, ms: the cost of work run on one thread, unaffected by other
/// processes on the machine except through shared caches.
double thread_cpu_ms();

/// The machine's 1-, 5- and 15-minute load averages ({-1, -1, -1} if unknown): recorded beside
/// timings taken on shared cores.
std::array<double, 3> load_averages();

}  // namespace meltlab
