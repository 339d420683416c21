// Time against error of the P measure (Eq. 8.1) at camera resolutions: two discs of radius
// r = 0.2 W whose centres are r apart, in images from 512x384 to 4096x3072 (discs scaled with
// the image). For each resolution:
//   raster    compare_masks on binary masks (the monograph's pixel count)
//   coverage  compare_coverage on 4x4-supersampled coverage images
//   contour   region_from_image(coverage, 0.5) for both + compare_regions_exact (CGAL)
//   marching  region_from_image alone (one image), the contour extraction cost
// The inputs are built once per resolution, outside the timed loop. Every benchmark reports
// abs_error = |P - P_analytic| (the lens closed form) and P in its counters.
// Timed by CPU time (single-threaded code). Run: meltlab_bench_p_measure --benchmark_repetitions=5
// --benchmark_report_aggregates_only=true

#include <meltlab/verify/metrics.h>
#include <meltlab/verify/region.h>

#include <benchmark/benchmark.h>

#include <opencv2/core.hpp>

#include <cmath>
#include <map>
#include <mutex>

#include "shapes.h"  // tests/support: the discs and their closed forms

namespace {

using namespace meltlab::verify;
using meltlab::verify::testing::disc_coverage;
using meltlab::verify::testing::disc_mask;
using meltlab::verify::testing::disc_pair_P;

constexpr int kSuper = 4;

struct Inputs {
  double r = 0, d = 0, P = 0;
  cv::Mat mask_a, mask_b, cov_a, cov_b;
};

const Inputs& inputs(int width) {
  static std::mutex mu;
  static std::map<int, Inputs> cache;
  std::lock_guard<std::mutex> lock(mu);
  auto it = cache.find(width);
  if (it != cache.end()) return it->second;
  const int height = width * 3 / 4;
  Inputs in;
  in.r = 0.2 * width;
  in.d = in.r;
  in.P = disc_pair_P(in.r, in.d);
  // Off-lattice centres (fixed fractions) so the raster error is typical, not symmetric.
  const double cx = 0.5 * width - 0.5 * in.d + 0.381966, cy = 0.5 * height + 0.271828;
  in.mask_a = disc_mask(width, height, cx, cy, in.r);
  in.mask_b = disc_mask(width, height, cx + in.d, cy, in.r);
  in.cov_a = disc_coverage(width, height, cx, cy, in.r, kSuper);
  in.cov_b = disc_coverage(width, height, cx + in.d, cy, in.r, kSuper);
  return cache.emplace(width, std::move(in)).first->second;
}

void report(benchmark::State& state, const Inputs& in, double P) {
  state.counters["abs_error"] = std::abs(P - in.P);
  state.counters["P"] = P;
  state.counters["r_px"] = in.r;
}

void BM_RasterP(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(compare_masks(in.mask_a, in.mask_b));
  report(state, in, compare_masks(in.mask_a, in.mask_b).P);
}

void BM_CoverageP(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(compare_coverage(in.cov_a, in.cov_b));
  report(state, in, compare_coverage(in.cov_a, in.cov_b).P);
}

void BM_ContourExactP(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const Region a = region_from_image(in.cov_a, 0.5), b = region_from_image(in.cov_b, 0.5);
    benchmark::DoNotOptimize(compare_regions_exact(a, b));
  }
  const Region a = region_from_image(in.cov_a, 0.5), b = region_from_image(in.cov_b, 0.5);
  report(state, in, compare_regions_exact(a, b).P);
  state.counters["vertices"] = static_cast<double>(region_vertex_count(a) + region_vertex_count(b));
}

void BM_MarchingSquares(benchmark::State& state) {
  const Inputs& in = inputs(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(region_from_image(in.cov_a, 0.5));
  state.counters["vertices"] = static_cast<double>(region_vertex_count(region_from_image(in.cov_a, 0.5)));
  state.counters["r_px"] = in.r;
}

void sizes(benchmark::internal::Benchmark* b) {
  for (int w : {512, 1024, 2048, 4096}) b->Arg(w);
  // CPU time: the machine the numbers come from is shared; real time is printed alongside.
  b->ArgName("width")->Unit(benchmark::kMillisecond);
}

BENCHMARK(BM_RasterP)->Apply(sizes);
BENCHMARK(BM_CoverageP)->Apply(sizes);
BENCHMARK(BM_ContourExactP)->Apply(sizes);
BENCHMARK(BM_MarchingSquares)->Apply(sizes);

}  // namespace

BENCHMARK_MAIN();
