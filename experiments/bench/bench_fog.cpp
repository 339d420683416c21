// Per-pixel cost of seed 002's analytic airlight (fog/airlight.h) on one thread, beside its peer,
// uniform-step ray marching (fog/reference.h), on the same G-buffers: S1 (sphere, k_t 0.1, one
// spotlight) and S2 (street of four lamps, k_t 0.04), 128×96 as `meltlab fog bench --study speed`
// in quick mode. The analytic model uses the default H table (N = 64, cbrt / sqrt_hi / value). The
// marching steps are the coarsest ones whose median E2 against R-air is at most 1 % in that study
// (S1 0.03125 m, S2 0.125 m) and the coarsest ones whose p99 is (S1 0.00390625 m, S2 not reached
// at 0.0039 m: the finest step measured); the study finds them, this program only times them.
// Counter ns_per_pixel: time per pixel of the G-buffer (lit or not). Run with
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// and read the medians; the ratio march / analytic is the speed goal of issue 18 (≥ 30×).

#include <meltlab/render/fog/airlight.h>
#include <meltlab/render/fog/fog_frame.h>
#include <meltlab/render/fog/reference.h>
#include <meltlab/render/fog/scenes.h>

#include <benchmark/benchmark.h>

#include <vector>

namespace {

using namespace meltlab;
namespace fog = render::fog;

struct Case {
  fog::FogScene scene;
  fog::GBuffer g;
};

const Case& scene_case(int which) {
  static const Case s1 = [] {
    Case c{fog::scene_sphere(0.1, 128, 96), {}};
    c.g = fog::trace_analytic(c.scene);
    return c;
  }();
  static const Case s2 = [] {
    Case c{fog::scene_street(0.04, 128, 96, 4), {}};
    c.g = fog::trace_analytic(c.scene);
    return c;
  }();
  return which == 0 ? s1 : s2;
}

const fog::FogTableSet& default_tables() {
  static const fog::FogTableSet t = [] {
    fog::TableOptions to;  // N = 64
    to.u_warp = fog::AxisWarp::kCbrt;
    to.v_warp = fog::AxisWarp::kSqrtHi;
    to.v_interp = fog::InterpSpace::kValue;
    return fog::build_fog_tables(to, fog::TableFunction::kH, 20, false);
  }();
  return t;
}

void set_per_pixel(benchmark::State& state, const Case& c) {
  state.counters["ns_per_pixel"] =
      benchmark::Counter(static_cast<double>(c.g.pixels.size()) * 1e-9,
                         benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// Args: scene (0 = S1, 1 = S2).
void BM_AnalyticAirlight(benchmark::State& state) {
  const Case& c = scene_case(static_cast<int>(state.range(0)));
  const fog::FogFunctions fn = default_tables().functions();
  const fog::FogModelOptions o;
  std::vector<double> out(c.g.pixels.size());
  for (auto _ : state) {
    const std::vector<fog::PreparedLight> lights = fog::prepare_lights(c.scene.lights);  // once per frame
    for (std::size_t k = 0; k < c.g.pixels.size(); ++k) {
      double sum = 0;
      for (const auto& l : lights)
        sum += l.light.intensity *
               fog::airlight_unit(c.g.eye, c.g.pixels[k].dir, c.g.pixels[k].m, l, c.scene.medium, fn, o);
      out[k] = sum;
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  set_per_pixel(state, c);
}
BENCHMARK(BM_AnalyticAirlight)->ArgName("scene")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Args: scene, step in units of 2^-10 m.
void BM_MarchAirlight(benchmark::State& state) {
  const Case& c = scene_case(static_cast<int>(state.range(0)));
  const double step = static_cast<double>(state.range(1)) / 1024.0;
  std::vector<double> out(c.g.pixels.size());
  for (auto _ : state) {
    for (std::size_t k = 0; k < c.g.pixels.size(); ++k) {
      double sum = 0;
      for (const auto& l : c.scene.lights)
        sum += l.intensity * fog::march_airlight(c.g.eye, c.g.pixels[k].dir, c.g.pixels[k].m, l, c.scene.medium, step);
      out[k] = sum;
    }
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  set_per_pixel(state, c);
}
BENCHMARK(BM_MarchAirlight)
    ->ArgNames({"scene", "step_1024th_m"})
    ->Args({0, 32})   // S1, median E2 <= 1 %
    ->Args({0, 4})    // S1, p99 E2 <= 1 %
    ->Args({1, 128})  // S2, median E2 <= 1 %
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
