// The machine's limits that the parallel melt cycle and the renderers run into, measured in the
// same run as they are (docs/melt-core.md, "Issue 20, step 8"):
//  - BM_LoadLatency: dependent loads over a random cycle through a buffer of `kb` KB, one load per
//    64-byte line, on CPU `cpu`: where the L2 ends and how much of the L3 this CPU gets;
//  - BM_ReadBandwidth: the sum of a buffer of `mb` MB on CPU `cpu` (bytes per second);
//  - BM_LineRoundTrip: one cache line passed between threads on CPU 0 and CPU 1 and back: what a
//    value written on one CPU and read on the other costs;
//  - BM_ParallelRegionAfterGap: a TBB parallel_for of two 20 µs tasks after `gap_us` of serial work
//    (the melt cycle's passes, a statistics row): the time above 20 µs is what starting the region
//    costs, small while the worker still spins, large once it has gone to sleep.
// All pinned with pthread_setaffinity_np; on a machine with one CPU both "CPUs" are the same.

#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <numeric>
#include <random>
#include <thread>
#include <vector>

#include "pin_thread.h"

namespace {

using meltlab::bench::pin_this_thread;
using meltlab::bench::unpin_this_thread;

constexpr std::size_t kLine = 64;
constexpr std::size_t kWordsPerLine = kLine / sizeof(std::uint64_t);

void BM_LoadLatency(benchmark::State& state) {
  const auto cpu = static_cast<unsigned>(state.range(0));
  const auto lines = static_cast<std::size_t>(state.range(1)) * 1024 / kLine;
  pin_this_thread(cpu);
  // A single random cycle through all lines (Sattolo's shuffle), so the prefetchers cannot guess.
  std::vector<std::uint64_t> order(lines);
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(42);
  for (std::size_t i = lines - 1; i > 0; --i)
    std::swap(order[i], order[std::uniform_int_distribution<std::size_t>(0, i - 1)(rng)]);
  std::vector<std::uint64_t> next(lines * kWordsPerLine);
  for (std::size_t i = 0; i < lines; ++i) next[i * kWordsPerLine] = order[i] * kWordsPerLine;
  constexpr std::int64_t kLoadsPerIteration = 1 << 16;
  std::uint64_t p = 0;
  for (std::size_t i = 0; i < lines; ++i) p = next[p];  // warm
  for (auto _ : state) {
    for (std::int64_t i = 0; i < kLoadsPerIteration; ++i) p = next[p];
    benchmark::DoNotOptimize(p);
  }
  state.counters["ns_per_load"] = benchmark::Counter(static_cast<double>(state.iterations() * kLoadsPerIteration),
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  unpin_this_thread();
}

void BM_ReadBandwidth(benchmark::State& state) {
  const auto cpu = static_cast<unsigned>(state.range(0));
  const auto words = static_cast<std::size_t>(state.range(1)) * 1024 * 1024 / sizeof(std::uint64_t);
  pin_this_thread(cpu);
  std::vector<std::uint64_t> data(words, 1);
  for (auto _ : state) benchmark::DoNotOptimize(std::accumulate(data.begin(), data.end(), std::uint64_t{0}));
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(words * sizeof(std::uint64_t)));
  unpin_this_thread();
}

void BM_LineRoundTrip(benchmark::State& state) {
  alignas(kLine) std::atomic<std::int64_t> turn{0};
  std::thread echo([&] {
    pin_this_thread(1);
    for (std::int64_t expect = 1;; expect += 2) {
      std::int64_t v;
      while ((v = turn.load(std::memory_order_acquire)) != expect && v >= 0) {
      }
      if (v < 0) return;
      turn.store(expect + 1, std::memory_order_release);
    }
  });
  pin_this_thread(0);
  std::int64_t sent = 1;
  for (auto _ : state) {
    turn.store(sent, std::memory_order_release);
    while (turn.load(std::memory_order_acquire) != sent + 1) {
    }
    sent += 2;
  }
  turn.store(-1, std::memory_order_release);
  echo.join();
  unpin_this_thread();
}

void spin_us(double us) {
  const auto t0 = std::chrono::steady_clock::now();
  while (std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() < us) {
  }
}

void BM_ParallelRegionAfterGap(benchmark::State& state) {
  const auto gap_us = static_cast<double>(state.range(0));
  constexpr double kTaskUs = 20;
  double region_us = 0;
  for (auto _ : state) {
    spin_us(gap_us);
    const auto t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(
        tbb::blocked_range<int>(0, 2, 1), [](const tbb::blocked_range<int>&) { spin_us(kTaskUs); },
        tbb::simple_partitioner());
    region_us += std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  }
  state.counters["start_us"] = region_us / static_cast<double>(state.iterations()) - kTaskUs;
}

void latency_args(benchmark::internal::Benchmark* b) {
  for (int cpu : {0, 1})
    for (int kb : {64, 512, 1024, 2048, 4096, 8192, 16384, 65536}) b->Args({cpu, kb});
  b->ArgNames({"cpu", "kb"});
}

}  // namespace

BENCHMARK(BM_LoadLatency)->Apply(latency_args)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ReadBandwidth)->ArgsProduct({{0, 1}, {256}})->ArgNames({"cpu", "mb"})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LineRoundTrip)->Unit(benchmark::kNanosecond);
BENCHMARK(BM_ParallelRegionAfterGap)
    ->ArgsProduct({{0, 50, 100, 200, 500, 1000, 5000}})
    ->ArgNames({"gap_us"})
    ->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
