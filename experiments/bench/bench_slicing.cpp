// Seed 003's slicing renderer (render/slicing/) against the one volume integrator's ray caster at
// equal sample density: seed 001's skull-like phantom (256 x 256 x 68 uint8, spacing 1 : 1 : 2 in
// a 256 x 256 x 136 box) standing in for seed 003's CT phantom, the spec's 30° camera at
// 1000 x 730, the same piecewise-constant TF (the skull table, opaque bone, here α 0.3) in both.
// Slicing Blend at QC (plane spacing Δd = QC · h0); the ray caster's TF model with fixed steps
// Δs = QC · h0, shading off, no ERT, empty-space skipping off (slicing has none) or on.
// Wall-clock time (UseRealTime; both run on TBB threads); the ratio of medians in one run is the
// comparison (the machine is shared).
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/slicing/slicing_renderer.h>
#include <meltlab/render/volume/generate.h>

#include <benchmark/benchmark.h>

#include <cmath>

namespace {

using namespace meltlab;

const render::Volume& skull() {
  static const render::Volume v = [] {
    render::VolumeGenerateOptions g;
    g.kind = render::VolumeKind::kSkull;
    g.nx = 256, g.ny = 256, g.nz = 68;
    g.shapes.seed = 1;
    render::Volume out = render::generate_volume(g);
    out.fit_to_box(render::Box3{Eigen::Vector3d(-128, -128, -68), Eigen::Vector3d(128, 128, 68)});
    return out;
  }();
  return v;
}

render::Camera camera() {
  const double fy = 0.5 * 730 / std::tan(15.0 * M_PI / 180);
  return render::Pinhole::look_at(1000, 730, fy, Eigen::Vector3d(420, -560, 300).normalized() * 620,
                                  Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
}

render::TransferFunction bone() {
  std::vector<render::TfRange> r(1);
  r[0] = {40, 240, false, false, Eigen::Vector3d(255, 250, 240), 0.3};
  return render::TransferFunction(r, "bone");
}

// arg: QC x 100
void BM_SlicingBlend(benchmark::State& state) {
  render::SlicingSettings s;
  s.quality_class = double(state.range(0)) / 100;
  s.value_range = std::make_pair(0.0, 1.0);  // raw values: the same table as the ray caster's
  s.tfs[0] = bone();
  const render::SlicingRenderer r(skull(), s);
  const auto cam = camera();
  std::int64_t samples = 0;
  for (auto _ : state) {
    const auto f = r.render(cam);
    samples = f.stats.samples;
    benchmark::DoNotOptimize(f.rgb.data());
  }
  state.counters["samples"] = double(samples);
  state.counters["ns_per_sample"] = benchmark::Counter(
      double(samples) * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// args: QC x 100, empty-space skipping (0/1)
void BM_RayCastTf(benchmark::State& state) {
  render::VolumeRenderSettings s;
  s.model = render::OpticalModel::kTransferFunction;
  s.tf.table = bone();
  s.tf.shading.enabled = false;
  s.step_rule = render::StepRule::kFixedStep;
  s.step = double(state.range(0)) / 100 * skull().spacing().minCoeff();
  s.skip_empty = state.range(1) != 0;
  s.ert_transmittance = 0;
  const render::VolumeTracer tracer(skull(), s);
  const auto cam = camera();
  std::int64_t samples = 0;
  for (auto _ : state) {
    const auto f = tracer.render(cam);
    samples = f.stats.samples;
    benchmark::DoNotOptimize(f.radiance.data());
  }
  state.counters["samples"] = double(samples);
  state.counters["ns_per_sample"] = benchmark::Counter(
      double(samples) * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

BENCHMARK(BM_SlicingBlend)->Arg(100)->Arg(200)->Arg(400)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RayCastTf)
    ->Args({100, 0})
    ->Args({100, 1})
    ->Args({200, 0})
    ->Args({400, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
