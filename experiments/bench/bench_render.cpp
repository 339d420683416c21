// Frame time of the ice/liquid ray tracer (integrator/ice_surface.h) on the bunny (bunny00, 75 408
// triangles, the monograph's "bunny ≈ 69k" of Fig. 6.10) at 1024x768, automatic camera, a wet
// ground (the mask after 60 deposit cycles of the bunny's footprint), and the cost of the
// terms that a scene can switch off (the skip-what-is-not-needed rule of design.md):
//   full          monograph material, dispersion, liquid (all terms)
//   no_dispersion one refraction instead of three lookups
//   reflect_only  ct = 0: no refraction, no dispersion
//   no_liquid     sublimation: no mask
//   minimal       ct = 0, cs = 0, no liquid, cr = 0 on the ground
//   physical      the physically based reference (refraction in and out, Beer, traced)
//   full_mipmap   full with texture_filter: mipmap (OpenImageIO TextureSystem lookups with
//                 footprints from ray differentials instead of point-sampled bilinear ones)
//   physical_mipmap  physical with texture_filter: mipmap
// plus the per-cycle BVH update (refit and rebuild), and the scaling of Tab. 6.1 / Fig. 6.11:
// the full frame of 1, 4 and 9 copies of the 871 414-triangle dragon (dataset dragon_871k,
// CGAL's Chinese dragon refined; 9 copies = 7 842 726 triangles) standing in a grid, each
// with its own wet footprint. Wall-clock time (UseRealTime): the tiles
// run on TBB threads. Run with
//   --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
// and read the medians.

#include <meltlab/datasets/catalog.h>
#include <meltlab/datasets/mesh_transforms.h>
#include <meltlab/render/embree/mesh_bvh.h>
#include <meltlab/render/texture/filtered.h>
#include <meltlab/render/integrator/ice_surface.h>
#include <meltlab/sim/liquid_mask.h>
#include <meltlab/sim/mesh_io.h>

#include <benchmark/benchmark.h>

#include <Eigen/Geometry>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace meltlab;

// A y-up dataset (the CGAL files) standing on z = 0, rotated as `meltlab render --up y`.
sim::IndexedMesh standing(const std::string& dataset) {
  sim::IndexedMesh im = sim::load_mesh(datasets::dataset_path(dataset)).mesh;
  for (auto& v : im.V) v = sim::Vec3<double>(v.z(), v.x(), v.y());
  double zmin = im.V[0].z();
  for (const auto& v : im.V) zmin = std::min(zmin, v.z());
  for (auto& v : im.V) v.z() -= zmin;
  return im;
}

const sim::TriMesh<double>& bunny() {
  static const sim::TriMesh<double> m = sim::TriMesh<double>::from_indexed(standing("bunny00"));
  return m;
}

// The wet ground: the mask after 60 deposit cycles of the mesh's footprint.
std::unique_ptr<sim::LiquidMask> wet_mask_of(const sim::TriMesh<double>& mesh) {
  auto p = sim::LiquidMaskParams::around(mesh.to_indexed(), 256, 3.0);
  p.threshold = 0.25f;
  auto m = std::make_unique<sim::LiquidMask>(p);
  for (int c = 0; c < 60; ++c) m->step(mesh, true);
  return m;
}

const sim::LiquidMask& wet_mask() {
  static const std::unique_ptr<sim::LiquidMask> mask = wet_mask_of(bunny());
  return *mask;
}

// The timed loop: one warm-up frame (it also logs the plan), then a frame per iteration.
void time_frames(benchmark::State& state, render::IceRenderer& r) {
  render::RgbImage img = r.render();
  for (auto _ : state) {
    img = r.render();
    benchmark::DoNotOptimize(img.data());
  }
}

enum Variant { kFull, kNoDispersion, kReflectOnly, kNoLiquid, kMinimal, kPhysical, kFullMipmap, kPhysicalMipmap };
const char* kNames[] = {"full",    "no_dispersion", "reflect_only", "no_liquid",
                        "minimal", "physical",      "full_mipmap",  "physical_mipmap"};

void BM_RenderBunny(benchmark::State& state) {
  const auto v = static_cast<Variant>(state.range(0));
  render::RenderScene s;
  s.width = 1024;
  s.height = 768;
  bool liquid = true;
  switch (v) {
    case kFull:
      break;
    case kNoDispersion:
      s.ice.dispersion = false;
      break;
    case kReflectOnly:
      s.ice.ct = 0;
      break;
    case kNoLiquid:
      liquid = false;
      break;
    case kMinimal:
      s.ice.ct = 0;
      s.ice.cs = 0;
      s.ground.cs = 0;
      liquid = false;
      break;
    case kPhysical:
      s.ice.model = render::IceModel::kPhysical;
      break;
    case kFullMipmap:
      s.texture_filter = render::TextureFilter::kMipmap;
      break;
    case kPhysicalMipmap:
      s.ice.model = render::IceModel::kPhysical;
      s.texture_filter = render::TextureFilter::kMipmap;
      break;
  }
  render::IceRenderer r(s);
  r.set_mesh(bunny());
  if (liquid) r.set_liquid(&wet_mask());
  time_frames(state, r);
  state.SetLabel(std::string(kNames[v]) + " 1024x768");
  state.counters["triangles"] = static_cast<double>(bunny().live_triangle_count());
  state.counters["skipped_terms"] = static_cast<double>(r.plan().skipped.size());
}
BENCHMARK(BM_RenderBunny)->DenseRange(0, 7)->Unit(benchmark::kMillisecond)->UseRealTime();

// Fig. 6.11: frame time against the number of dragons (arg), full material and wet ground.
// The copies stand on a square grid with a gap of a fifth of the dragon's footprint.
void BM_RenderDragons(benchmark::State& state) {
  const int copies = static_cast<int>(state.range(0));
  const int side = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(copies))));
  const sim::IndexedMesh one = standing("dragon_871k");
  Eigen::AlignedBox3d box;
  for (const auto& v : one.V) box.extend(v);
  const double pitch = 1.2 * std::max(box.sizes().x(), box.sizes().y());
  sim::IndexedMesh all;
  for (int k = 0; k < copies; ++k) {
    const Eigen::Vector3d offset((k % side) * pitch, (k / side) * pitch, 0.0);
    all = k == 0 ? datasets::translated(one, offset) : datasets::merged(all, datasets::translated(one, offset));
  }
  const sim::TriMesh<double> mesh = sim::TriMesh<double>::from_indexed(all);
  const auto mask = wet_mask_of(mesh);
  render::RenderScene s;
  s.width = 1024;
  s.height = 768;
  render::IceRenderer r(s);
  r.set_mesh(mesh);
  r.set_liquid(mask.get());
  time_frames(state, r);
  state.SetLabel(std::to_string(copies) + " dragon(s) 1024x768");
  state.counters["triangles"] = static_cast<double>(mesh.live_triangle_count());
}
BENCHMARK(BM_RenderDragons)->Arg(1)->Arg(4)->Arg(9)->Unit(benchmark::kMillisecond)->UseRealTime();

// args: 0 = refit (positions moved), 1 = rebuild (triangles changed)
// One texture lookup of the 256x256 ground texture at 4096 scattered points: the bilinear
// RgbImage lookup (arg 0) against OpenImageIO's TextureSystem with a zero footprint (1), an
// isotropic footprint of 4 texels (2) and an 8:1 anisotropic one (3).
void BM_TextureLookup(benchmark::State& state) {
  const render::RgbImage tex = render::ground_texture(256, 1);
  render::FilteredTextures ft;
  const int id = ft.add(tex, render::FilteredTextures::Kind::kTexture, "ground");
  std::vector<Eigen::Vector2d> st(4096);
  for (std::size_t k = 0; k < st.size(); ++k)
    st[k] = Eigen::Vector2d(std::fmod(0.6180339887 * static_cast<double>(k), 1.0),
                            std::fmod(0.7548776662 * static_cast<double>(k), 1.0));
  const double texel = 1.0 / 256;
  const Eigen::Vector2d dx = state.range(0) == 2 ? Eigen::Vector2d(4 * texel, 0) : Eigen::Vector2d(8 * texel, 0);
  const Eigen::Vector2d dy = state.range(0) == 2 ? Eigen::Vector2d(0, 4 * texel) : Eigen::Vector2d(0, texel);
  for (auto _ : state) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& p : st) {
      switch (state.range(0)) {
        case 0:
          sum += sample_bilinear_rgb(tex, p.x() * 256 - 0.5, p.y() * 256 - 0.5, ImageWrap::kRepeat, ImageWrap::kRepeat);
          break;
        case 1:
          sum += ft.texture(id, p.x(), p.y(), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero());
          break;
        default:
          sum += ft.texture(id, p.x(), p.y(), dx, dy);
          break;
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(st.size()));
  const char* names[] = {"bilinear", "oiio point", "oiio 4 texels", "oiio 8:1 aniso"};
  state.SetLabel(names[state.range(0)]);
}
BENCHMARK(BM_TextureLookup)->DenseRange(0, 3);

void BM_BvhUpdate(benchmark::State& state) {
  render::MeshBvh bvh;
  sim::TriMesh<double> m = bunny();
  bvh.update(m);
  const bool rebuild = state.range(0) != 0;
  int flip = 0;
  for (auto _ : state) {
    if (rebuild) {
      m.triangle_alive[0] = static_cast<std::uint8_t>(flip ^= 1);
    } else {
      for (auto& z : m.position.z()) z += 1e-6;
    }
    benchmark::DoNotOptimize(bvh.update(m));
  }
  state.SetLabel(rebuild ? "rebuild" : "refit");
}
BENCHMARK(BM_BvhUpdate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// One liquid cycle (spread + deposit of the bunny's footprint) on a 256² mask.
void BM_LiquidCycle(benchmark::State& state) {
  auto p = sim::LiquidMaskParams::around(bunny().to_indexed(), static_cast<int>(state.range(0)), 3.0);
  sim::LiquidMask m(p);
  for (auto _ : state) m.step(bunny(), true);
  state.SetLabel(std::to_string(state.range(0)) + "^2 mask");
}
BENCHMARK(BM_LiquidCycle)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
