// Time per melt cycle against triangle count, serial and parallel, float and double — the
// monograph's Tab. 5.1 (objects A/B/C: 192, 16000, 32000 triangles; stand-ins of equal size:
// a subdivided cube and two UV spheres, whose pole regions collapse in the first cycles)
// extended with uniform geodesic spheres of 32k, 100k and 1M triangles and two real scanned
// meshes (the 75k bunny, the 871k refined dragon; both also in breadth-first order) — and the
// OpenMesh half-edge peer in the same run;
// and the cost of one row of the per-cycle statistics beside it; what the time between two
// cycles (a row, a busy wait, a sleep) costs the next one (BM_MeltCycleAfterGap); and the
// ceiling of two threads on this machine: two serial cycles at once on their own copies of the
// mesh, pinned to CPU 0 and CPU 1, sharing no data (BM_IndependentCopies).
//
// Every benchmark melts its mesh for a warm-up (the UV spheres' pole regions collapse in the
// first cycles), then times cycles from that state, restarting from it every
// kCyclesPerRestart cycles so the triangle count stays within a few percent of its label.
// Results: run with --benchmark_out=FILE --benchmark_out_format=json (scripts/bench does).

#include <meltlab/datasets/catalog.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/melt.h>
#include <meltlab/sim/mesh_io.h>
#include <meltlab/sim/mesh_order.h>
#include <meltlab/sim/mesh_stats.h>
#include <meltlab/sim/quality.h>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <latch>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "openmesh_peer.h"
#include "pin_thread.h"

namespace {

using namespace meltlab;

constexpr int kWarmupCycles = 20;
constexpr int kCyclesPerRestart = 20;

// The same coefficients everywhere (the CLI defaults): kE = 0.05 L0 per cycle, kN = kE/100, kr = 0.5 L0.
sim::MeltParams bench_params(const sim::IndexedMesh& m) { return sim::relative_melt_params(m); }

const sim::IndexedMesh& input_mesh(int id) {
  static std::mutex mu;
  static std::map<int, sim::IndexedMesh> cache;
  std::lock_guard<std::mutex> lock(mu);
  auto it = cache.find(id);
  if (it != cache.end()) return it->second;
  sim::IndexedMesh m;
  switch (id) {
    case 0:
      m = datasets::benchmark_object('A');
      break;
    case 1:
      m = datasets::benchmark_object('B');
      break;
    case 2:
      m = datasets::benchmark_object('C');
      break;
    case 3:
      m = datasets::geodesic_sphere(71, 0.05);
      break;  // 100820 triangles
    case 4:
      m = datasets::geodesic_sphere(224, 0.05);
      break;  // 1003520 triangles
    case 5:
      m = sim::reorder_for_locality(sim::load_mesh(datasets::dataset_path("bunny00")).mesh).mesh;
      break;
    case 6:
      m = datasets::geodesic_sphere(40, 0.05);
      break;  // 32000 triangles, uniform
    case 7:   // 871414 triangles, a refined scan in Morton order (as the CLI loads it)
      m = sim::reorder_for_locality(sim::load_mesh(datasets::dataset_path("dragon_871k")).mesh).mesh;
      break;
    case 8:  // the same two scans breadth-first (`meltlab simulate --order bfs`)
      m = sim::reorder_breadth_first(sim::load_mesh(datasets::dataset_path("dragon_871k")).mesh).mesh;
      break;
    case 9:
      m = sim::reorder_breadth_first(sim::load_mesh(datasets::dataset_path("bunny00")).mesh).mesh;
      break;
    case 10:
      m = sim::reorder_breadth_first(datasets::geodesic_sphere(40, 0.05)).mesh;
      break;
    case 11:
      m = sim::reorder_for_locality(datasets::geodesic_sphere(40, 0.05)).mesh;
      break;
    default:
      break;
  }
  return cache.emplace(id, std::move(m)).first->second;
}

const char* mesh_label(int id) {
  static const char* labels[] = {
      "A_192",        "B_16k",       "C_32k",      "geodesic_100k", "geodesic_1M",      "bunny_75k",
      "geodesic_32k", "dragon_871k", "dragon_bfs", "bunny_bfs",     "geodesic_32k_bfs", "geodesic_32k_morton"};
  return labels[id];
}

// The melted state after the warm-up, per mesh and precision.
template <class Real>
const sim::TriMesh<Real>& warm_state(int id) {
  static std::mutex mu;
  static std::map<int, sim::TriMesh<Real>> cache;
  std::lock_guard<std::mutex> lock(mu);
  auto it = cache.find(id);
  if (it != cache.end()) return it->second;
  const sim::IndexedMesh& m = input_mesh(id);
  sim::MeltSimulator<Real> s(sim::TriMesh<Real>::from_indexed(m), bench_params(m), sim::make_constant_kl(1.0));
  for (int c = 0; c < kWarmupCycles; ++c) s.step();
  return cache.emplace(id, s.mesh()).first->second;
}

// Times one step() of `make()`'s simulator per iteration, making a fresh one from the warm state
// every kCyclesPerRestart cycles (outside the timing), and hands each cycle's report to `seen`.
// The iteration time mixes three kinds of cycle, which the counters give apart (wall ms, means):
// `first_ms` the first cycle of a fresh simulator (it also sets up its workspace: the sweep's
// schedule and the first touch of its arrays, which a long run pays once), `check_ms` the cycles
// that ran the remnant check (every 16th; in the benchmark always its first, in a fresh workspace)
// and `steady_ms` all other cycles (docs/melt-core.md, issue 20 step 17).
template <class Make, class Seen>
void time_cycles(benchmark::State& state, const Make& make, const Seen& seen) {
  auto cycle = make();
  int since_restart = 0;
  double sum_ms[3] = {0, 0, 0};  // first, check, steady
  double count[3] = {0, 0, 0};
  for (auto _ : state) {
    if (since_restart == kCyclesPerRestart) {
      state.PauseTiming();
      cycle = make();
      since_restart = 0;
      state.ResumeTiming();
    }
    const auto t0 = std::chrono::steady_clock::now();
    const sim::CycleReport r = cycle->step();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    benchmark::DoNotOptimize(r);
    const int kind = since_restart == 0 ? 0 : r.remnant_ms > 0 ? 1 : 2;
    sum_ms[kind] += ms, count[kind] += 1;
    seen(r);
    ++since_restart;
  }
  const char* names[3] = {"first_ms", "check_ms", "steady_ms"};
  for (int k = 0; k < 3; ++k)
    if (count[k] > 0) state.counters[names[k]] = sum_ms[k] / count[k];
}

/// TBB limited to one thread, or left all of them.
tbb::global_control thread_limit(bool parallel) {
  return tbb::global_control(tbb::global_control::max_allowed_parallelism,
                             parallel ? static_cast<std::size_t>(tbb::info::default_concurrency()) : 1);
}

template <class Real>
const char* precision_name() {
  return std::is_same_v<Real, float> ? "float" : "double";
}

template <class Real>
void BM_MeltCycle(benchmark::State& state) {
  const int id = static_cast<int>(state.range(0));
  const bool parallel = state.range(1) != 0;
  const tbb::global_control threads = thread_limit(parallel);
  const sim::MeltParams p = bench_params(input_mesh(id));
  const sim::TriMesh<Real>& start = warm_state<Real>(id);
  const auto exec = parallel ? sim::Execution::kParallel : sim::Execution::kSerial;
  double triangles = 0, deform_ms = 0, collapse_ms = 0, glued_ms = 0, repair_ms = 0, remnant_ms = 0, compact_ms = 0;
  time_cycles(
      state, [&] { return std::make_unique<sim::MeltSimulator<Real>>(start, p, sim::make_constant_kl(1.0), exec); },
      [&](const sim::CycleReport& r) {
        triangles += static_cast<double>(r.live_triangles);
        deform_ms += r.deform_ms;
        collapse_ms += r.collapse_ms;
        glued_ms += r.glued_ms;
        repair_ms += r.repair_ms;
        remnant_ms += r.remnant_ms;
        compact_ms += r.compact_ms;
      });
  state.counters["triangles"] = benchmark::Counter(triangles, benchmark::Counter::kAvgIterations);
  // Where a cycle's time goes (the simulator's own clocks, per cycle: the remnant check runs
  // every 16th cycle, the compaction when the dead slots call for one; the rest of the cycle
  // is the live counts).
  state.counters["deform_ms"] = benchmark::Counter(deform_ms, benchmark::Counter::kAvgIterations);
  state.counters["collapse_ms"] = benchmark::Counter(collapse_ms, benchmark::Counter::kAvgIterations);
  state.counters["glued_ms"] = benchmark::Counter(glued_ms, benchmark::Counter::kAvgIterations);
  state.counters["repair_ms"] = benchmark::Counter(repair_ms, benchmark::Counter::kAvgIterations);
  state.counters["remnant_ms"] = benchmark::Counter(remnant_ms, benchmark::Counter::kAvgIterations);
  state.counters["compact_ms"] = benchmark::Counter(compact_ms, benchmark::Counter::kAvgIterations);
  state.counters["threads"] = parallel ? tbb::info::default_concurrency() : 1;
  state.SetLabel(std::string(mesh_label(id)) + (parallel ? " parallel " : " serial ") + precision_name<Real>());
}

// The parallel cycle's work on one thread: the sweep in `parts` parts (interior groups, the
// stored terms of split vertices, the halo groups) run one after another. Against
// BM_MeltCycle/parallel:0 (one part) it is the extra work of the partition; against
// BM_MeltCycle/parallel:1 (two parts on two threads) it separates that work from what the
// two CPUs cost each other.
template <class Real>
void BM_MeltCycleInParts(benchmark::State& state) {
  const int id = static_cast<int>(state.range(0));
  const auto parts = static_cast<std::size_t>(state.range(1));
  const tbb::global_control threads = thread_limit(false);
  const sim::MeltParams p = bench_params(input_mesh(id));
  const sim::TriMesh<Real>& start = warm_state<Real>(id);
  auto make = [&] {
    auto s = std::make_unique<sim::MeltSimulator<Real>>(start, p, sim::make_constant_kl(1.0), sim::Execution::kSerial);
    s->set_sweep_parts(parts);
    return s;
  };
  double deform_ms = 0;
  time_cycles(state, make, [&](const sim::CycleReport& r) { deform_ms += r.deform_ms; });
  state.counters["deform_ms"] = benchmark::Counter(deform_ms, benchmark::Counter::kAvgIterations);
  state.SetLabel(std::string(mesh_label(id)) + " " + std::to_string(parts) + " parts serial " + precision_name<Real>());
}

// The same cycle on OpenMesh's half-edge mesh with its own collapse operations (serial).
template <class Real>
void BM_OpenMeshPeer(benchmark::State& state) {
  const int id = static_cast<int>(state.range(0));
  const sim::IndexedMesh start = warm_state<Real>(id).to_indexed();
  const sim::MeltParams p = bench_params(input_mesh(id));
  double triangles = 0;
  time_cycles(
      state, [&] { return std::make_unique<bench::OpenMeshMeltPeerT<Real>>(start, p); },
      [&](const sim::CycleReport& r) { triangles += static_cast<double>(r.live_triangles); });
  state.counters["triangles"] = benchmark::Counter(triangles, benchmark::Counter::kAvgIterations);
  state.SetLabel(std::string(mesh_label(id)) + " openmesh-peer serial " + precision_name<Real>());
}

// One row of `meltlab simulate`'s per-cycle statistics (Euler counts and quality measures) on
// the warm state, with the object kept between rows as the CLI keeps it: its cost against a
// cycle's (BM_MeltCycle on the same mesh in the same run).
template <class Real>
void BM_MeshStatistics(benchmark::State& state) {
  const int id = static_cast<int>(state.range(0));
  const bool parallel = state.range(1) != 0;
  const tbb::global_control threads = thread_limit(parallel);
  const sim::TriMesh<Real>& mesh = warm_state<Real>(id);
  sim::MeshStatistics stats;
  for (auto _ : state) benchmark::DoNotOptimize(stats.compute(mesh).quality.Qd);
  state.counters["triangles"] = static_cast<double>(mesh.live_triangle_count());
  state.SetLabel(std::string(mesh_label(id)) + (parallel ? " parallel " : " serial ") + precision_name<Real>());
}

// What the time between cycles costs the next cycle: `meltlab simulate` writes a statistics row
// after every cycle by default, and its median cycle (step() alone) is then much slower than with
// rare rows. Each iteration here first spends a gap outside the timing, then times one step() of
// the parallel double cycle (the CLI's defaults). Gaps: none; one statistics row (as the CLI);
// a busy wait of 1 or 4 ms (one CPU spins on the clock, no memory traffic); a sleep of 1 or 4 ms.
// If a busy wait slows the next cycle about as much as a row of the same length, the row's cost
// to the cycle is its time away from the mesh (during which the host's other tenants evict the
// cycle's data from the shared caches), not its own memory traffic. Counter: gap_ms, the gap's
// measured length.
enum class Gap { kNone, kStatisticsRow, kBusy1ms, kBusy4ms, kSleep1ms, kSleep4ms };

void spend_gap(Gap gap, sim::MeshStatistics& stats, const sim::TriMesh<double>& mesh) {
  using Clock = std::chrono::steady_clock;
  const auto busy = [](std::chrono::microseconds d) {
    const auto end = Clock::now() + d;
    while (Clock::now() < end) {
    }
  };
  switch (gap) {
    case Gap::kNone:
      break;
    case Gap::kStatisticsRow:
      benchmark::DoNotOptimize(stats.compute(mesh).quality.Qd);
      break;
    case Gap::kBusy1ms:
      busy(std::chrono::microseconds(1000));
      break;
    case Gap::kBusy4ms:
      busy(std::chrono::microseconds(4000));
      break;
    case Gap::kSleep1ms:
      std::this_thread::sleep_for(std::chrono::microseconds(1000));
      break;
    case Gap::kSleep4ms:
      std::this_thread::sleep_for(std::chrono::microseconds(4000));
      break;
  }
}

const char* gap_label(Gap gap) {
  static const char* labels[] = {"no gap", "statistics row", "busy 1 ms", "busy 4 ms", "sleep 1 ms", "sleep 4 ms"};
  return labels[static_cast<int>(gap)];
}

void BM_MeltCycleAfterGap(benchmark::State& state) {
  using Clock = std::chrono::steady_clock;
  const int id = static_cast<int>(state.range(0));
  const auto gap = static_cast<Gap>(state.range(1));
  const tbb::global_control threads = thread_limit(true);
  const sim::MeltParams p = bench_params(input_mesh(id));
  const sim::TriMesh<double>& start = warm_state<double>(id);
  auto make = [&] {
    return std::make_unique<sim::MeltSimulator<double>>(start, p, sim::make_constant_kl(1.0),
                                                        sim::Execution::kParallel);
  };
  auto cycle = make();
  sim::MeshStatistics stats;
  int since_restart = 0;
  double gap_s = 0;
  for (auto _ : state) {
    if (since_restart == kCyclesPerRestart) cycle = make(), since_restart = 0;
    const auto g0 = Clock::now();
    spend_gap(gap, stats, cycle->mesh());
    const auto t0 = Clock::now();
    benchmark::DoNotOptimize(cycle->step());
    const auto t1 = Clock::now();
    state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    gap_s += std::chrono::duration<double>(t0 - g0).count();
    ++since_restart;
  }
  state.counters["gap_ms"] = benchmark::Counter(gap_s * 1e3, benchmark::Counter::kAvgIterations);
  state.SetLabel(std::string(mesh_label(id)) + " parallel double after " + gap_label(gap));
}

// `copies` serial cycles at once, each on its own copy of the warm state, made and melted by
// a thread pinned to CPU k: no data is shared between them, so their summed throughput is the
// most that `copies` threads can give on this machine, the ceiling of
// BM_MeltCycle<Real>/mesh/parallel:1 on the same mesh. An iteration: every thread makes its copy,
// all start together, each times kCyclesPerRestart cycles (the iteration's time is the slowest
// copy's). Counters: each copy's ms per cycle, and ms_per_cycle = 1 / (summed cycles per ms).
template <class Real>
void BM_IndependentCopies(benchmark::State& state) {
  const int id = static_cast<int>(state.range(0));
  const auto copies = static_cast<std::size_t>(state.range(1));
  const sim::MeltParams p = bench_params(input_mesh(id));
  const sim::TriMesh<Real>& start = warm_state<Real>(id);
  std::vector<double> copy_s(copies, 0.0), iteration_s(copies, 0.0);
  for (auto _ : state) {
    std::latch ready(static_cast<std::ptrdiff_t>(copies));
    std::vector<std::thread> threads;
    for (std::size_t k = 0; k < copies; ++k)
      threads.emplace_back([&, k] {
        bench::pin_this_thread(static_cast<unsigned>(k));
        sim::MeltSimulator<Real> s(start, p, sim::make_constant_kl(1.0), sim::Execution::kSerial);
        ready.arrive_and_wait();
        const auto t0 = std::chrono::steady_clock::now();
        for (int c = 0; c < kCyclesPerRestart; ++c) benchmark::DoNotOptimize(s.step());
        iteration_s[k] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        copy_s[k] += iteration_s[k];
      });
    for (auto& t : threads) t.join();
    state.SetIterationTime(*std::max_element(iteration_s.begin(), iteration_s.end()));
  }
  const auto cycles_per_copy = static_cast<double>(state.iterations() * kCyclesPerRestart);
  double cycles_per_ms = 0;
  for (std::size_t k = 0; k < copies; ++k) {
    const double ms = copy_s[k] * 1e3 / cycles_per_copy;
    state.counters["cpu" + std::to_string(k) + "_ms"] = ms;
    cycles_per_ms += 1.0 / ms;
  }
  state.counters["ms_per_cycle"] = 1.0 / cycles_per_ms;
  state.SetLabel(std::string(mesh_label(id)) + " " + std::to_string(copies) + (copies == 1 ? " copy " : " copies ") +
                 precision_name<Real>());
}

void meshes_and_modes(benchmark::internal::Benchmark* b) {
  for (int id : {0, 1, 2, 6, 5, 3, 7, 4, 8, 9, 10, 11})
    for (int parallel : {0, 1}) b->Args({id, parallel});
  b->ArgNames({"mesh", "parallel"});
  b->Unit(benchmark::kMillisecond);
  b->MinTime(0.5);
}
void peer_meshes(benchmark::internal::Benchmark* b) {
  for (int id : {0, 1, 2, 6, 5, 3}) b->Args({id});
  b->ArgNames({"mesh"});
  b->Unit(benchmark::kMillisecond);
  b->MinTime(0.5);
}

// Object C, the geodesic 32k, the bunny and the dragon (breadth-first), each with 1 and 2 of
// `what` (parts of the sweep on one thread, or independent copies on two CPUs).
void meshes_with_one_and_two(benchmark::internal::Benchmark* b, const char* what) {
  for (int id : {2, 6, 9, 8})
    for (int n : {1, 2}) b->Args({id, n});
  b->ArgNames({"mesh", what});
  b->Unit(benchmark::kMillisecond);
  b->MinTime(0.5);
}
// The bunny as the CLI loads it and object C, after each kind of gap.
void gap_meshes(benchmark::internal::Benchmark* b) {
  for (int id : {5, 2})
    for (int gap = 0; gap <= static_cast<int>(Gap::kSleep4ms); ++gap) b->Args({id, gap});
  b->ArgNames({"mesh", "gap"});
  b->Unit(benchmark::kMillisecond);
  b->MinTime(0.5);
  b->UseManualTime();
}
void parts_meshes(benchmark::internal::Benchmark* b) { meshes_with_one_and_two(b, "parts"); }
void copies_meshes(benchmark::internal::Benchmark* b) {
  meshes_with_one_and_two(b, "copies");
  b->UseManualTime();
}

}  // namespace

BENCHMARK(BM_MeltCycle<float>)->Apply(meshes_and_modes);
BENCHMARK(BM_MeltCycle<double>)->Apply(meshes_and_modes);
BENCHMARK(BM_OpenMeshPeer<float>)->Apply(peer_meshes);
BENCHMARK(BM_MeshStatistics<double>)->Apply(meshes_and_modes);
BENCHMARK(BM_OpenMeshPeer<double>)->Apply(peer_meshes);
BENCHMARK(BM_MeltCycleInParts<float>)->Apply(parts_meshes);
BENCHMARK(BM_MeltCycleInParts<double>)->Apply(parts_meshes);
BENCHMARK(BM_IndependentCopies<float>)->Apply(copies_meshes);
BENCHMARK(BM_IndependentCopies<double>)->Apply(copies_meshes);
BENCHMARK(BM_MeltCycleAfterGap)->Apply(gap_meshes);

BENCHMARK_MAIN();
