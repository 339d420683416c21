// Volume ray casting (render/integrator/volume_integrator.h) on the seed-000 scenes: the 300-unit
// box of turbulence (64³ or 128³), a point light at (2d, 2d, 2d), a pinhole camera that sees the
// whole box; the models Emission, HG and HGAttenuated (shadow march and shadow cache) at 50, 64,
// 100 samples per ray and 256² / 512² pixels (the source's Tables 5.1-5.3), and the empty-space
// skipping and ERT switches. Wall-clock time (UseRealTime; the renderer runs on TBB threads).
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// `meltlab volume bench` runs the same scenes for the report (tables, scaling fits, Pareto, the
// OpenVDB peer); this program is for profiling and quick comparisons.

#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/volume/generate.h>

#include <benchmark/benchmark.h>

#include <map>

namespace {

using namespace meltlab;
using render::OpticalModel;

const render::Volume& turbulence(int n) {
  static std::map<int, render::Volume> cache;
  auto it = cache.find(n);
  if (it == cache.end()) {
    render::VolumeGenerateOptions g;
    g.kind = render::VolumeKind::kTurbulenceBox;
    g.nx = g.ny = g.nz = n;
    render::Volume v = render::generate_volume(g);
    v.fit_to_box(render::Box3{Eigen::Vector3d::Constant(-150), Eigen::Vector3d::Constant(150)});
    it = cache.emplace(n, v).first;
  }
  return it->second;
}

render::Camera camera(int side) {
  return render::Pinhole::look_at(side, side, 0.5 * side / std::tan(22.5 * 3.14159265358979 / 180),
                                  Eigen::Vector3d(400, -550, 300), Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
}

// args: model (0 emission, 1 HG, 2 HGAttenuated march, 3 HGAttenuated cache), samples, image side,
// volume side
void BM_Volume(benchmark::State& state) {
  const int model = int(state.range(0));
  render::VolumeRenderSettings s;
  s.model = model == 0 ? OpticalModel::kEmission : model == 1 ? OpticalModel::kHG : OpticalModel::kHGAttenuated;
  s.shadow = model == 3 ? render::ShadowMethod::kCache : render::ShadowMethod::kMarch;
  s.samples = int(state.range(1));
  s.kappa = 0.01;
  s.emission = render::Rgb(0.004, 0.003, 0.002);
  const auto cam = camera(int(state.range(2)));
  const auto& vol = turbulence(int(state.range(3)));
  std::int64_t samples = 0;
  for (auto _ : state) {
    const auto f = render::render_volume(vol, cam, s);
    samples = f.stats.samples + f.stats.shadow_samples;
    benchmark::DoNotOptimize(f.radiance.data());
  }
  state.counters["samples"] = double(samples);
  static const char* names[] = {"Emission", "HG", "HGAtt-march", "HGAtt-cache"};
  state.SetLabel(std::string(names[model]) + " n=" + std::to_string(state.range(1)) + " " +
                 std::to_string(state.range(2)) + "^2 vol " + std::to_string(state.range(3)) + "^3");
}
BENCHMARK(BM_Volume)
    ->ArgsProduct({{0, 1, 3}, {50, 64, 100}, {256, 512}, {64}})
    ->Args({2, 50, 256, 64})
    ->Args({0, 50, 512, 128})
    ->Args({1, 50, 512, 128})
    ->Args({3, 50, 512, 128})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

}  // namespace

BENCHMARK_MAIN();
