#pragma once
// Benchmarks only: run the calling thread on one CPU (Linux), so a measurement names the CPU it
// was taken on. The two vCPUs of the development VM differ in the cache they share with other
// tenants (docs/melt-core.md, "Issue 20, step 8").

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <thread>

namespace meltlab::bench {

/// Pins the calling thread to CPU `cpu` modulo the CPUs there are; false if the system refused.
inline bool pin_this_thread(unsigned cpu) {
  const unsigned n = std::max(1u, std::thread::hardware_concurrency());
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu % n, &set);
  return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

/// Lets the calling thread run on every CPU again.
inline void unpin_this_thread() {
  const unsigned n = std::max(1u, std::thread::hardware_concurrency());
  cpu_set_t set;
  CPU_ZERO(&set);
  for (unsigned c = 0; c < n; ++c) CPU_SET(c, &set);
  pthread_setaffinity_np(pthread_self(), sizeof set, &set);
}

}  // namespace meltlab::bench
