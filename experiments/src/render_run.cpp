// `meltlab render` (render_run.h).

#include <meltlab/core/statistics.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/experiments/render_run.h>
#include <meltlab/experiments/render_json.h>
#include <meltlab/render/integrator/ice_surface.h>
#include <meltlab/render/texture/assets.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/experiments/provenance.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// A relief texture for the threshold (Fig. 7.7a): smooth value noise mapped to [p/2, 3p/2].
std::vector<float> relief_threshold(int w, int h, float p) {
  std::vector<float> tp(static_cast<std::size_t>(w) * h);
  auto hash = [](int i, int j) {
    std::uint64_t x =
        static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full;
    x ^= x >> 29;
    x *= 0xBF58476D1CE4E5B9ull;
    x ^= x >> 32;
    return static_cast<double>(x >> 11) * 0x1.0p-53;
  };
  const int cell = std::max(4, w / 16);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double x = static_cast<double>(i) / cell, y = static_cast<double>(j) / cell;
      const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
      const double fx = x - x0, fy = y - y0;
      const double sx = fx * fx * (3 - 2 * fx), sy = fy * fy * (3 - 2 * fy);
      const double n = (1 - sy) * ((1 - sx) * hash(x0, y0) + sx * hash(x0 + 1, y0)) +
                       sy * ((1 - sx) * hash(x0, y0 + 1) + sx * hash(x0 + 1, y0 + 1));
      tp[static_cast<std::size_t>(j) * w + i] = p * static_cast<float>(0.5 + n);
    }
  return tp;
}

std::string csv_text(const std::vector<std::string>& rows, const std::string& header) {
  std::string s = header + "\n";
  for (const auto& r : rows) s += r + "\n";
  return s;
}

void check_options(const RenderRunOptions& o) {
  require(o.cycles >= 0, fmt::format("--cycles: must be >= 0 (got {})", o.cycles));
  require(o.every >= 1, fmt::format("--every: must be >= 1 (got {})", o.every));
  require(o.mask_resolution >= 16 && o.mask_resolution <= 8192,
          fmt::format("--mask-resolution: must be in [16, 8192] (got {})", o.mask_resolution));
  require(o.threshold > 0.0f && std::isfinite(o.threshold), "--threshold: must be a finite number > 0");
  require(o.far_fraction > 0 && o.far_fraction <= 1,
          fmt::format("--far-fraction: must be in (0, 1] (got {})", o.far_fraction));
  require(o.mask_extent >= 1.0, fmt::format("--mask-extent: must be >= 1 (got {})", o.mask_extent));
  require(o.width >= 0 && o.height >= 0 && o.width <= 16384 && o.height <= 16384,
          "--width/--height: must be in [1, 16384]");
  require(o.up == 'x' || o.up == 'y' || o.up == 'z', fmt::format("--up: must be x, y or z (got '{}')", o.up));
  if (o.liquid_figure) {
    require(o.liquid, "--liquid-figure: needs the liquid stage (drop --no-liquid)");
    require(!o.figure_cycles.empty(), "--figure-cycles: give at least one cycle");
    for (auto c : o.figure_cycles) require(c >= 0, fmt::format("--figure-cycles: cycles must be >= 0 (got {})", c));
  }
}

// The mesh with its up axis turned to +z and, with place_on_ground, lifted by `lift` so its
// lowest point is on the ground z = 0. Cyclic axis permutations keep the orientation
// (outward normals stay outward).
sim::IndexedMesh standing_mesh(sim::IndexedMesh mesh, const RenderRunOptions& o, double& lift) {
  if (o.up == 'y')
    for (auto& v : mesh.V) v = sim::Vec3<double>(v.z(), v.x(), v.y());  // (x, y, z) -> (z, x, y): +y becomes +z
  else if (o.up == 'x')
    for (auto& v : mesh.V) v = sim::Vec3<double>(v.y(), v.z(), v.x());  // +x becomes +z
  lift = 0;
  if (o.place_on_ground && !mesh.V.empty()) {
    double zmin = mesh.V[0].z();
    for (const auto& v : mesh.V) zmin = std::min(zmin, v.z());
    lift = -zmin;
    for (auto& v : mesh.V) v.z() += lift;
  }
  return mesh;
}

// The liquid stage (nullptr: sublimation).
std::unique_ptr<sim::LiquidMask> liquid_mask(const RenderRunOptions& o, const sim::IndexedMesh& mesh) {
  if (!o.liquid) return nullptr;
  sim::LiquidMaskParams mp = sim::LiquidMaskParams::around(mesh, o.mask_resolution, o.mask_extent);
  mp.threshold = o.threshold;
  mp.far_fraction = o.far_fraction;
  mp.blend = o.blend;
  auto mask = std::make_unique<sim::LiquidMask>(mp);
  if (o.threshold_texture) mask->set_threshold_texture(relief_threshold(mp.width, mp.height, o.threshold));
  return mask;
}

// Fig. 7.6: the mask at `cycle` as liquid/mask_<cycle>.png; returns its mask_sums.csv row.
std::string write_mask_figure(const fs::path& dir, const sim::LiquidMask& mask, std::int64_t cycle, int digits,
                              std::int64_t triangles) {
  const std::string name = fmt::format("mask_{:0{}}.png", cycle, digits);
  render::write_gray_png(dir / "liquid" / name, mask.values(), mask.params().width, mask.params().height,
                         mask.params().deposit_value);
  return fmt::format("{},{},{:.9g},{},{:.9g}", cycle, triangles, mask.total(), mask.wet_count(),
                     static_cast<double>(mask.max_value()));
}

// A frame of the melting mesh `m` at `cycle` into frames/; returns its frames.csv row.
std::string write_frame(const fs::path& dir, render::IceRenderer& renderer, const sim::TriMesh<double>& m,
                        const sim::LiquidMask* mask, std::int64_t cycle, int digits, std::int64_t triangles) {
  renderer.set_mesh(m);
  const render::RgbImage img = renderer.render();
  const auto& st = renderer.last_stats();
  const std::string stem = fmt::format("frame_{:0{}}", cycle, digits);
  const render::RenderOutputs& out = renderer.scene().outputs;
  if (out.exr) render::write_exr(dir / "frames" / (stem + ".exr"), img);
  if (out.png) render::write_png(dir / "frames" / (stem + ".png"), img, out.exposure, out.gamma);
  const char* bvh = st.bvh == render::BvhUpdate::kRefit     ? "refit"
                    : st.bvh == render::BvhUpdate::kRebuild ? "rebuild"
                                                            : "none";
  return fmt::format("{},{},{},{:.3f},{:.3f},{:.9g},{}", cycle, triangles, bvh, st.bvh_ms, st.trace_ms,
                     mask ? mask->total() : 0.0, mask ? mask->wet_count() : 0);
}

// render.json without the provenance.
json run_record(const RenderRunOptions& o, const PreparedSimulation& prepared, double lift, std::int64_t last,
                const RenderRunResult& result, const sim::LiquidMask* mask, const render::IceRenderer* renderer,
                int threads) {
  json j;
  j["mesh"] = prepared.mesh_json;
  j["mesh_up_axis"] = std::string(1, o.up);
  j["mesh_lift_z"] = lift;
  j["melt"] = {
      {"kg", prepared.params.kg}, {"kE", prepared.params.kE}, {"kN", prepared.params.kN}, {"kr", prepared.params.kr}};
  j["cycles"] = {{"requested", last}, {"run", result.cycles_run}, {"melted_at_cycle", result.melted_at_cycle}};
  if (mask) {
    const auto& mp = mask->params();
    j["liquid"] = {{"mask_resolution", mp.width},
                   {"mask_format", "float32, one channel"},
                   {"texel_size", mp.texel_size},
                   {"origin", {mp.origin.x(), mp.origin.y()}},
                   {"p_threshold", static_cast<double>(mp.threshold)},
                   {"threshold_texture", o.threshold_texture ? "relief value noise in [p/2, 3p/2]" : "none"},
                   {"deposit_far_fraction", mp.far_fraction},
                   {"deposit_slab", "z_min .. z_min + far_fraction (z_max - z_min) of the live mesh, every cycle"},
                   {"deposit_value", static_cast<double>(mp.deposit_value)},
                   {"deposit_blend", mp.blend == sim::DepositBlend::kOverwrite ? "overwrite" : "add"},
                   {"liquid_steps_per_cycle", "1 spread + 1 deposit"},
                   {"border_mode", "zero"}};
  } else {
    j["liquid"] = "off (no liquid stage)";
  }
  if (!renderer) {
    j["liquid_figure_cycles"] = o.figure_cycles;
  } else {
    j["scene"] = render_scene_json(renderer->scene());
    j["camera"] = camera_json(renderer->camera());
    j["skipped"] = renderer->plan().skipped;
    j["frames"] = result.frames;
    j["median_trace_ms"] = result.median_trace_ms;
  }
  j["threads"] = threads;
  return j;
}

}  // namespace

RenderRunResult run_render(const RenderRunOptions& o) {
  // ---- validate everything before touching the output folder ----
  check_options(o);
  render::RenderScene scene =
      o.scene_file.empty() ? render::RenderScene{} : render::load_render_scene(o.scene_file.string());
  if (o.width > 0) scene.width = o.width;
  if (o.height > 0) scene.height = o.height;
  auto prepared = prepare_simulation(o.melt, /*check_output=*/false);
  RunFolder folder(o.out_dir, {"--out", "render.json", "run", o.overwrite});
  Provenance provenance = start_provenance("render", o.command_line);
  const fs::path& dir = folder.path();

  // ---- set up: the mesh on the ground, the melt, the liquid, the renderer ----
  double lift = 0;
  const sim::IndexedMesh mesh = standing_mesh(prepared->mesh, o, lift);
  const int threads = o.melt.threads == 0 ? tbb::info::default_concurrency() : o.melt.threads;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  const sim::Execution exec = threads == 1 ? sim::Execution::kSerial : sim::Execution::kParallel;
  sim::MeltSimulator<double> simulator(sim::TriMesh<double>::from_indexed(mesh), prepared->params, prepared->kl, exec);
  std::unique_ptr<sim::LiquidMask> mask = liquid_mask(o, mesh);
  create_output_directories(dir, "--out");
  const bool figure = o.liquid_figure;
  const std::int64_t last = figure ? *std::max_element(o.figure_cycles.begin(), o.figure_cycles.end()) : o.cycles;
  const std::set<std::int64_t> figure_at(o.figure_cycles.begin(), o.figure_cycles.end());
  const int digits = std::max(6, static_cast<int>(std::to_string(last).size()));
  std::unique_ptr<render::IceRenderer> renderer;
  if (!figure) {
    create_output_directories(dir / "frames", "--out");
    renderer = std::make_unique<render::IceRenderer>(scene);
    renderer->set_liquid(mask.get());
  }
  if (figure) create_output_directories(dir / "liquid", "--out");

  // ---- the melt, a frame (or a mask) at the cycles asked for ----
  RenderRunResult result;
  std::vector<std::string> rows;
  std::vector<double> trace_ms;
  for (std::int64_t cycle = 0;; ++cycle) {
    const auto& m = simulator.mesh();
    const auto triangles = static_cast<std::int64_t>(m.live_triangle_count());
    if (figure && figure_at.count(cycle)) rows.push_back(write_mask_figure(dir, *mask, cycle, digits, triangles));
    if (!figure && (cycle % o.every == 0 || cycle == last)) {
      rows.push_back(write_frame(dir, *renderer, m, mask.get(), cycle, digits, triangles));
      trace_ms.push_back(renderer->last_stats().trace_ms);
      ++result.frames;
    }
    if (cycle >= last) break;
    if (!simulator.empty())
      simulator.step();
    else if (result.melted_at_cycle < 0)
      result.melted_at_cycle = cycle;
    if (mask) mask->step(simulator.mesh(), exec == sim::Execution::kParallel);
    result.cycles_run = cycle + 1;
  }

  // ---- outputs ----
  if (figure) {
    write_text_atomically(dir / "liquid" / "mask_sums.csv",
                          csv_text(rows, "cycle,triangles,mask_sum,wet_texels,mask_max"));
  } else {
    write_text_atomically(dir / "frames.csv",
                          csv_text(rows, "cycle,triangles,bvh_update,bvh_ms,trace_ms,mask_sum,wet_texels"));
  }
  result.median_trace_ms = median(trace_ms);
  json j = run_record(o, *prepared, lift, last, result, mask.get(), renderer.get(), threads);
  result.run_json = commit_run(folder, std::move(j), provenance);
  return result;
}

}  // namespace meltlab::experiments
