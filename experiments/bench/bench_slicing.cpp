// Seed 003's slicing renderer (render/slicing/) against the one volume integrator's ray caster at
// equal sample density: seed 001's skull-like phantom (256 x 256 x 68 uint8, spacing 1 : 1 : 2 in
// a 256 x 256 x 136 box) standing in for seed 003's CT phantom, the spec's 30° camera at
// 1000 x 730, the same piecewise-constant TF (the skull table, opaque bone, here α 0.3) in both.
// Slicing Blend at QC (plane spacing Δd = QC · h0); the ray caster's TF model with fixed steps
// Δs = QC · h0, shading off, no ERT, empty-space skipping off or on.
// Wall-clock time (UseRealTime; both run on TBB threads); the ratio of medians in one run is the
// comparison (the machine is shared).
//
// Seed 003's own case (issue 17 §4): the CT phantom (render/volume/ct_phantom.h, 256 x 256 x 113
// int16 HU at spacing 1 : 1 : 2, noise σ 20 HU, seed 1) normalised to [0, 1] by its scanned extrema
// as the scene's `generate: {kind: ct_phantom}` does (float32), at 1000 x 730 with the 30° camera
// placed so that the head covers about 70 % of the frame (the `coverage` counter: the share of
// pixels with α > 0.01), one piecewise-constant TF readable by both renderers, a CT preset in
// normalised values (the scanned range is about −1100 … 1100 HU): skin (0.23, 0.455] ≈ −600 … −100
// HU α 0.05 (the air–fat transition and the fat layer), bone (0.75, 1] ≈ above 550 HU α 0.6;
// water, muscle and air invisible. Blend at QC 0.5, 1, 2 (args: QC × 100, empty-space cell edge in
// voxels, early termination × 1000, 0 = off, tile edge, 0 = 16: the default renderer is /4/0/0), the
// scene's piecewise-linear TF ("head" of slicing_phantom_*.yaml) at QC 1, the combined mode at
// QC 1 (gradients radius 2, 8 bits, built once outside the timing), Blend with an all-ones mask
// (100³) at QC 1 for both TFs, the ray caster at equal
// density (Δs = QC · h0) without and with its empty-space skipping. Counters: samples (plane
// samples, jumped ones included), visited (positions computed), fetched (fetch bit set),
// cell_tests (one ray at a time: visited samples whose empty-space cell was looked up, the others in
// live runs; packets: planes bounded per block of pixels), terminated (early termination). CPU time
// of the whole process (MeasureProcessCPUTime: every TBB thread) beside the wall time, since the
// cores are shared: "CPU" / "Time" ≈ the cores the frame kept busy.
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
//   --benchmark_filter=Phantom   (issue 17's goal: BM_PhantomBlend/100/4/0/0 <= 150 ms)

#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/slicing/slicing_renderer.h>
#include <meltlab/core/image.h>
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

/// The ray caster's TF model at the slicing's sample density (fixed step QC x h0 = state.range(0)
/// / 100 x the smallest spacing; empty-space skipping if state.range(1)), no shading, no ERT.
void ray_cast_frames(benchmark::State& state, const render::Volume& volume, const render::Camera& cam,
                     const render::TransferFunction& tf) {
  render::VolumeRenderSettings s;
  s.model = render::OpticalModel::kTransferFunction;
  s.tf.table = tf;
  s.tf.shading.enabled = false;
  s.step_rule = render::StepRule::kFixedStep;
  s.step = double(state.range(0)) / 100 * volume.spacing().minCoeff();
  s.skip_empty = state.range(1) != 0;
  s.ert_transmittance = 0;
  const render::VolumeTracer tracer(volume, s);
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
void BM_RayCastTf(benchmark::State& state) { ray_cast_frames(state, skull(), camera(), bone()); }

// --- seed 003's CT phantom ---

const render::Volume& phantom() {
  static const render::Volume v = [] {
    render::VolumeGenerateOptions g;
    g.kind = render::VolumeKind::kCtPhantom;
    g.nx = 256, g.ny = 256, g.nz = 113;
    return render::generate_volume(g);
  }();
  return v;
}

render::Camera phantom_camera() {
  const Eigen::Vector3d centre = phantom().domain().centre();
  const double fy = 0.5 * 730 / std::tan(15.0 * M_PI / 180);
  return render::Pinhole::look_at(1000, 730, fy, centre + Eigen::Vector3d(420, -560, 300).normalized() * 380, centre,
                                  Eigen::Vector3d::UnitZ());
}

render::TransferFunction phantom_tf() {
  std::vector<render::TfRange> r(2);
  r[0] = {0.23, 0.455, false, true, Eigen::Vector3d(230, 170, 140), 0.05};
  r[1] = {0.75, 1.0, false, true, Eigen::Vector3d(255, 250, 240), 0.6};
  return render::TransferFunction(r, "skin_bone");
}

double coverage(const ImageF& alpha) {
  std::int64_t n = 0;
  for (std::size_t i = 0; i < alpha.size(); ++i) n += alpha.values()[i] > 0.01f;
  return double(n) / double(alpha.size());
}

void slicing_counters(benchmark::State& state, const render::SlicingStats& st, double cover) {
  state.counters["samples"] = double(st.samples);
  state.counters["fetched"] = double(st.samples - st.skipped);
  state.counters["terminated"] = double(st.terminated);
  state.counters["visited"] = double(st.visited);
  state.counters["cell_tests"] = double(st.cell_tests);
  state.counters["coverage"] = cover;
  state.counters["ns_per_sample"] = benchmark::Counter(
      double(st.samples) * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

/// Frames of the phantom at its camera, each rendered into the last one's images as a loop of
/// frames renders them (render_into: no new memory after the first), and the renderer's counters.
void time_renderer(benchmark::State& state, const render::SlicingRenderer& r) {
  const auto cam = phantom_camera();
  render::SlicingFrame f;
  double render_ms = 0, post_ms = 0;
  for (auto _ : state) {
    r.render_into(cam, f);
    benchmark::DoNotOptimize(f.rgb.data());
    render_ms += f.stats.render_ms;
    post_ms += f.stats.post_ms;
  }
  slicing_counters(state, f.stats, coverage(f.alpha));
  // Where a frame's wall time goes: the renderer's loop over the tiles, and the colour
  // adjustment and bloom after it (SlicingStats).
  state.counters["render_ms"] = benchmark::Counter(render_ms, benchmark::Counter::kAvgIterations);
  state.counters["post_ms"] = benchmark::Counter(post_ms, benchmark::Counter::kAvgIterations);
}

/// time_renderer of the phantom with settings s.
void time_phantom(benchmark::State& state, const render::SlicingSettings& s) {
  time_renderer(state, render::SlicingRenderer(phantom(), s));
}

// args: QC x 100, empty-space cell edge (voxels), early termination x 1000 (0: off)
void BM_PhantomBlend(benchmark::State& state) {
  render::SlicingSettings s;
  s.quality_class = double(state.range(0)) / 100;
  s.skip_cell = int(state.range(1));
  s.early_termination = double(state.range(2)) / 1000;
  if (state.range(3) > 0) s.tile = int(state.range(3));
  s.tfs[0] = phantom_tf();
  time_phantom(state, s);
}

/// The scene's piecewise-linear TF (experiments/configs/volume/slicing_phantom_ones.yaml, "head").
render::TransferFunction phantom_linear_tf() {
  const double rows[6][5] = {{0.40, 0.95, 0.72, 0.60, 0}, {0.445, 0.95, 0.72, 0.60, 0.02}, {0.462, 0.95, 0.72, 0.60, 0},
                             {0.62, 0.82, 0.78, 0.7, 0},  {0.80, 0.82, 0.78, 0.7, 0.025},  {1, 0.82, 0.78, 0.7, 0.025}};
  std::array<render::TfCurve, 4> curves;
  for (const auto& r : rows)
    for (int c = 0; c < 4; ++c) curves[std::size_t(c)].points.emplace_back(r[0], r[c + 1]);
  return render::TransferFunction::piecewise_linear(curves, "head");
}

// The scene's linear TF (seed 003's phantom scenes, evaluated exactly per sample); arg: QC x 100
void BM_PhantomBlendLinear(benchmark::State& state) {
  render::SlicingSettings s;
  s.quality_class = double(state.range(0)) / 100;
  s.tfs[0] = phantom_linear_tf();
  time_phantom(state, s);
}

// The mask lookup's cost: an all-ones mask at the scenes' resolution (100³, TF 1 everywhere: the
// image of no mask); args: QC x 100, TF (0: the bench's constant TF, 1: the scene's linear TF)
void BM_PhantomBlendMasked(benchmark::State& state) {
  render::SlicingSettings s;
  s.quality_class = double(state.range(0)) / 100;
  s.tfs[0] = state.range(1) != 0 ? phantom_linear_tf() : phantom_tf();
  s.mask = render::MaskVolume({100, 100, 100}, phantom().domain(), 1);
  time_phantom(state, s);
}

// The voxel bits' effect (SlicingSettings::skip_voxels; the same image either way); args: QC x 100,
// voxel bits (0/1), TF (0: the bench's constant TF, 1: the scene's linear TF)
void BM_PhantomVoxelBits(benchmark::State& state) {
  render::SlicingSettings s;
  s.quality_class = double(state.range(0)) / 100;
  s.skip_voxels = state.range(1) != 0;
  s.tfs[0] = state.range(2) != 0 ? phantom_linear_tf() : phantom_tf();
  time_phantom(state, s);
}

// What a renderer costs to set up on the phantom (the empty-space cells, their distance maps and,
// with arg 1, the voxel bits; no gradients): once per volume and settings, before any frame.
void BM_PhantomSetUp(benchmark::State& state) {
  render::SlicingSettings s;
  s.skip_voxels = state.range(0) != 0;
  s.tfs[0] = phantom_tf();
  for (auto _ : state) {
    render::SlicingRenderer r(phantom(), s);
    benchmark::DoNotOptimize(&r);
  }
}

// The packets against one ray at a time on this machine (SlicingSettings::simd; the same image
// either way); args: QC x 100, packets (0/1)
void BM_PhantomPackets(benchmark::State& state) {
  render::SlicingSettings s;
  s.quality_class = double(state.range(0)) / 100;
  s.simd = state.range(1) != 0;
  s.tfs[0] = phantom_tf();
  time_phantom(state, s);
}

// args: QC x 100, empty-space cell edge (voxels)
void BM_PhantomCombined(benchmark::State& state) {
  render::SlicingSettings s;
  s.mode = render::SlicingMode::kCombined;
  s.quality_class = double(state.range(0)) / 100;
  s.skip_cell = int(state.range(1));
  s.tfs[0] = phantom_tf();
  static const render::GradientVolume grad = render::build_gradient_volume(phantom(), s.gradient);
  time_renderer(state, render::SlicingRenderer(phantom(), s, grad));
}

// args: QC x 100, empty-space skipping (0/1)
void BM_PhantomRayCast(benchmark::State& state) { ray_cast_frames(state, phantom(), phantom_camera(), phantom_tf()); }

// Every benchmark here: milliseconds per frame, wall time (the goal's measure) beside the
// process's CPU time (all cores).
void frame_timing(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
}

BENCHMARK(BM_PhantomBlend)
    ->Args({50, 4, 0, 0})
    ->Args({100, 4, 0, 0})
    ->Args({200, 4, 0, 0})
    ->Args({100, 2, 0, 0})
    ->Args({100, 8, 0, 0})
    ->Args({100, 4, 990, 0})
    ->Args({50, 4, 990, 0})
    ->Args({200, 4, 990, 0})
    ->Args({100, 4, 0, 4})
    ->Args({100, 4, 0, 8})
    ->Args({100, 4, 0, 32})
    ->Args({100, 4, 0, 64})
    ->Args({50, 2, 0, 0})
    ->Args({200, 2, 0, 0})
    ->Args({100, 2, 990, 0})
    ->Apply(frame_timing);
BENCHMARK(BM_PhantomBlendLinear)->Arg(100)->Apply(frame_timing);
BENCHMARK(BM_PhantomBlendMasked)->Args({100, 0})->Args({100, 1})->Apply(frame_timing);
BENCHMARK(BM_PhantomVoxelBits)
    ->Args({100, 0, 0})
    ->Args({100, 1, 0})
    ->Args({100, 0, 1})
    ->Args({100, 1, 1})
    ->Apply(frame_timing);
BENCHMARK(BM_PhantomSetUp)->Arg(0)->Arg(1)->Apply(frame_timing);
BENCHMARK(BM_PhantomPackets)->Args({100, 0})->Args({100, 1})->Apply(frame_timing);
BENCHMARK(BM_PhantomCombined)->Args({100, 8})->Args({100, 4})->Apply(frame_timing);
BENCHMARK(BM_PhantomRayCast)->Args({100, 0})->Args({100, 1})->Apply(frame_timing);

BENCHMARK(BM_SlicingBlend)->Arg(100)->Arg(200)->Arg(400)->Apply(frame_timing);
BENCHMARK(BM_RayCastTf)->Args({100, 0})->Args({100, 1})->Args({200, 0})->Args({400, 0})->Apply(frame_timing);

}  // namespace

BENCHMARK_MAIN();
