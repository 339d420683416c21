// Photo-like ice rendering time (render/integrator/ice_photo.h): a 40 x 40 x 30 mm voxel block
// (h = 0.5 mm, 120 x 120 x 70 cells) on the ground, seen by a pinhole camera at 0.35 m, at
// 320x240 ... 1280x960 and primary step h/4, h/2, h; one sample per pixel; shadows from the
// light-transmittance grid (default) and, at the smallest size, the per-sample shadow march
// (HGAttenuated). ice_true_mask timing alongside.
//
// Wall-clock time (UseRealTime): the renderer works on TBB threads; the CPU column is the
// whole process's CPU time (all threads), which is the fairer figure on a loaded machine. Run with
//   --benchmark_repetitions=3 --benchmark_report_aggregates_only=true

#include <meltlab/datasets/molds.h>
#include <meltlab/render/integrator/ice_photo.h>
#include <meltlab/sim/physics/voxelize.h>

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>

namespace {

using namespace meltlab;
using render::Vec3d;

constexpr std::array<std::array<int, 2>, 3> kSizes = {{{320, 240}, {640, 480}, {1280, 960}}};

const sim::physics::IceFraction& block() {
  static const sim::physics::IceFraction g = [] {
    const double h = 0.5e-3;
    sim::physics::IceFraction b(120, 120, 70, h, Vec3d(-0.03, -0.03, 0.0), 0.0f);
    for (int k = 0; k < b.nz; ++k)
      for (int j = 0; j < b.ny; ++j)
        for (int i = 0; i < b.nx; ++i) {
          const Vec3d c = b.centre_m(i, j, k);
          if (std::abs(c.x()) < 0.02 && std::abs(c.y()) < 0.02 && c.z() < 0.03) b.at(i, j, k) = 1.0f;
        }
    return b;
  }();
  return g;
}

render::Camera camera_for(int size_index) {
  const auto [w, h] = kSizes[std::size_t(size_index)];
  // The block fills ~60% of the image height at every size.
  return render::Pinhole::look_at(w, h, 1400.0 * h / 300.0, Vec3d(0.02, -0.03, 0.35), Vec3d(0, 0, 0.01));
}

// args: size index, step as h / arg, shadow (0 grid, 1 march)
void BM_IcePhoto(benchmark::State& state) {
  const int si = int(state.range(0));
  render::IcePhotoOptions o;
  o.step_m = block().h_m / double(state.range(1));
  o.shadow = state.range(2) ? render::IcePhotoOptions::Shadow::kMarch : render::IcePhotoOptions::Shadow::kGrid;
  const auto cam = camera_for(si);
  for (auto _ : state) {
    cv::Mat img = render::render_ice_photo(block(), cam, o);
    benchmark::DoNotOptimize(img.data);
  }
  const auto [w, h] = kSizes[std::size_t(si)];
  state.SetLabel(std::to_string(w) + "x" + std::to_string(h) + " step h/" + std::to_string(state.range(1)) +
                 (state.range(2) ? " march" : " grid"));
}
BENCHMARK(BM_IcePhoto)
    ->Args({0, 2, 0})
    ->Args({1, 2, 0})
    ->Args({2, 2, 0})
    ->Args({1, 1, 0})
    ->Args({1, 4, 0})
    ->Args({0, 2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

// The production case: a 250 g giraffe mold block (153 x 184 x 30.5 mm) voxelized at h = arg mm
// (2 → 81 x 96 x 18 cells with the margin), seen from 0.7 m above, slightly oblique, at
// 1024x768 (the block fills ~60% of the image height); default options (step h/2, grid shadows).
const sim::physics::IceFraction& giraffe(int h_mm_x10) {
  static std::array<sim::physics::IceFraction, 3> cache;
  const std::size_t slot = h_mm_x10 == 15 ? 0 : h_mm_x10 == 20 ? 1 : 2;
  if (cache[slot].empty()) {
    sim::physics::VoxelizeOptions vo;
    vo.h_m = h_mm_x10 * 1e-4;
    cache[slot] = sim::physics::voxelize_fraction(datasets::mold_mesh(datasets::Mold::kGiraffe), vo);
  }
  return cache[slot];
}

void BM_IcePhotoGiraffe(benchmark::State& state) {
  const auto& g = giraffe(int(state.range(0)));
  const int w = int(state.range(1)), h = w * 3 / 4;
  const render::Camera cam =
      render::Pinhole::look_at(w, h, 1750.0 * h / 768.0, Vec3d(0.05, -0.08, 0.7), Vec3d(0, 0, 0.015));
  render::IcePhotoOptions o;
  for (auto _ : state) {
    cv::Mat img = render::render_ice_photo(g, cam, o);
    benchmark::DoNotOptimize(img.data);
  }
  state.SetLabel("giraffe h=" + std::to_string(state.range(0) / 10.0).substr(0, 3) + "mm " + std::to_string(g.nx) +
                 "x" + std::to_string(g.ny) + "x" + std::to_string(g.nz) + " " + std::to_string(w) + "x" +
                 std::to_string(h));
}
BENCHMARK(BM_IcePhotoGiraffe)
    ->Args({20, 1024})
    ->Args({15, 1024})
    ->Args({25, 1024})
    ->Args({20, 320})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MeasureProcessCPUTime();

void BM_IceTrueMask(benchmark::State& state) {
  const int si = int(state.range(0));
  const auto cam = camera_for(si);
  for (auto _ : state) {
    cv::Mat m = render::ice_true_mask(block(), cam);
    benchmark::DoNotOptimize(m.data);
  }
}
BENCHMARK(BM_IceTrueMask)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
