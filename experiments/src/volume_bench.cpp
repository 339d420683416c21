// `meltlab volume bench` (see volume_bench.h).

#include <meltlab/experiments/csv_table.h>
#include <meltlab/core/time.h>
#include <meltlab/core/statistics.h>
#include <meltlab/experiments/volume_bench.h>
#include <meltlab/experiments/bench_studies.h>

#include "volume_bench_clv.h"
#include "volume_bench_slicing.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/vdb/openvdb.h>
#include <meltlab/render/volume/generate.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <numbers>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;
using render::OpticalModel;
using Vec3 = Eigen::Vector3d;

namespace {

const render::Box3 kBox300{Vec3::Constant(-150), Vec3::Constant(150)};

render::Volume turbulence(render::VolumeKind kind, int n) {
  render::VolumeGenerateOptions g;
  g.kind = kind;
  g.nx = g.ny = g.nz = n;
  render::Volume v = render::generate_volume(g);
  v.fit_to_box(kBox300);
  return v;
}

/// The seed's camera on Box300: the whole box in view.
render::Camera camera(int side) {
  return render::Pinhole::look_at(side, side, 0.5 * side / std::tan(22.5 * std::numbers::pi / 180),
                                  Vec3(400, -550, 300), Vec3::Zero(), Vec3::UnitZ());
}

/// The seed's scene settings for a model (the same medium and light for every model).
render::VolumeRenderSettings seed_settings(OpticalModel model, int n) {
  render::VolumeRenderSettings s;
  s.model = model;
  s.samples = n;
  s.kappa = 0.02;
  s.albedo = 0.9;
  s.hg_c = 0.5;
  s.emission = render::Rgb(0.004, 0.003, 0.002);
  render::VolumeLight l;
  l.position = Vec3(600, 600, 600);
  l.intensity = render::Rgb::Constant(0.6);
  s.lights = {l};
  return s;
}

struct Timed {
  double median_ms = 0, min_ms = 0, max_ms = 0;
  double cpu_ms = 0;  ///< median process CPU time per frame (all threads): steadier than wall time under load
  render::VolumeFrame frame;
  double cache_ms = 0;
};

/// warm-up frames, then `repeats` timed ones; shadow caches (if any) built once, timed apart.
Timed time_render(const render::Volume& v, const render::Camera& cam, const render::VolumeRenderSettings& s, int warmup,
                  int repeats) {
  Timed t;
  std::vector<render::ShadowCache> caches;
  if (s.model == OpticalModel::kHGAttenuated && s.shadow == render::ShadowMethod::kCache) {
    const auto t0 = std::chrono::steady_clock::now();
    const int n = int(render::effective_lights(v, s).size());
    for (int l = 0; l < n; ++l) caches.push_back(render::build_shadow_cache(v, s, l));
    t.cache_ms = ms_since(t0);
  }
  std::vector<double> ms, cpu;
  for (int i = 0; i < warmup + repeats; ++i) {
    const double c0 = process_cpu_ms();
    const auto t0 = std::chrono::steady_clock::now();
    t.frame = render::render_volume(v, cam, s, caches);
    if (i >= warmup) ms.push_back(ms_since(t0)), cpu.push_back(process_cpu_ms() - c0);
  }
  t.median_ms = median(ms);
  t.cpu_ms = median(cpu);
  t.min_ms = *std::min_element(ms.begin(), ms.end());
  t.max_ms = *std::max_element(ms.begin(), ms.end());
  return t;
}

/// Relative RMS difference of the pixel colours (over black) of two frames: sqrt(Σ|a - b|²/Σ|b|²).
double rel_rmse(const ImageF& a, const ImageF& b) {
  double d2 = 0, r2 = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = double(a.values()[i]) - double(b.values()[i]);
    d2 += d * d;
    r2 += double(b.values()[i]) * double(b.values()[i]);
  }
  return r2 > 0 ? std::sqrt(d2 / r2) : std::sqrt(d2);
}

void progress(const std::string& what) { std::fprintf(stderr, "meltlab: volume bench: %s\n", what.c_str()); }

const char* model_key(OpticalModel m, render::ShadowMethod sh) {
  switch (m) {
    case OpticalModel::kEmission:
      return "emission";
    case OpticalModel::kHG:
      return "hg";
    case OpticalModel::kHGAttenuated:
      return sh == render::ShadowMethod::kCache ? "hg_attenuated_cache" : "hg_attenuated";
    default:
      return "other";
  }
}

// ---- Tables 5.1-5.3 ----------------------------------------------------------------------------

void study_tables(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  struct Config {
    const char* table;
    int volume, pixels;
    std::vector<int> samples;
  };
  const std::vector<Config> configs = {
      {"5.1", 64, 512, {100, 64, 50}}, {"5.2", 64, 256, {100, 64}}, {"5.3", 128, 512, {50}}};
  CsvTable csv(
      "table,volume,pixels,samples,model,median_ms,min_ms,max_ms,fps,primary_samples,shadow_samples,cache_build_ms,"
      "cpu_ms");
  std::map<int, render::Volume> volumes;
  for (const auto& c : configs) {
    if (!volumes.count(c.volume)) volumes.emplace(c.volume, turbulence(render::VolumeKind::kTurbulenceBox, c.volume));
    const auto& v = volumes.at(c.volume);
    for (int n : c.samples)
      for (auto [model, sh] : {std::pair{OpticalModel::kEmission, render::ShadowMethod::kMarch},
                               std::pair{OpticalModel::kHG, render::ShadowMethod::kMarch},
                               std::pair{OpticalModel::kHGAttenuated, render::ShadowMethod::kMarch},
                               std::pair{OpticalModel::kHGAttenuated, render::ShadowMethod::kCache}}) {
        auto s = seed_settings(model, n);
        s.shadow = sh;
        // The source's shadow march is O(n·m): a few frames of it say enough.
        const bool slow = model == OpticalModel::kHGAttenuated && sh == render::ShadowMethod::kMarch;
        const Timed t =
            time_render(v, camera(c.pixels), s, slow ? 0 : o.warmup, slow ? std::min(o.repeats, 3) : o.repeats);
        csv.row("{},{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{},{},{:.3f},{:.3f}", c.table, c.volume, c.pixels, n,
                model_key(model, sh), t.median_ms, t.min_ms, t.max_ms, 1000.0 / t.median_ms, t.frame.stats.samples,
                t.frame.stats.shadow_samples, t.cache_ms, t.cpu_ms);
        progress(fmt::format("Table {} {}³ {}² n={} {}: {:.1f} ms", c.table, c.volume, c.pixels, n,
                             model_key(model, sh), t.median_ms));
      }
  }
  csv.write(dir / "tables.csv");
  record["tables"] = {
      {"scene", "Box300 of turbulence_box, camera (400, -550, 300) fov 45, point light (600, 600, 600)"},
      {"kappa", 0.02},
      {"albedo", 0.9},
      {"hg_c", 0.5}};
}

// ---- scaling (targets 9, 10, 12) -----------------------------------------------------------------

void study_scaling(const VolumeBenchOptions& o, const fs::path& dir, json&) {
  CsvTable csv("kind,model,x,median_ms,primary_samples,shadow_samples");
  const auto v = turbulence(render::VolumeKind::kTurbulenceBox, 64);
  const int side = o.quick ? 128 : 256;
  for (auto [model, sh] : {std::pair{OpticalModel::kEmission, render::ShadowMethod::kMarch},
                           std::pair{OpticalModel::kHG, render::ShadowMethod::kMarch},
                           std::pair{OpticalModel::kHGAttenuated, render::ShadowMethod::kMarch},
                           std::pair{OpticalModel::kHGAttenuated, render::ShadowMethod::kCache}})
    for (int n : {50, 64, 100, 200}) {
      auto s = seed_settings(model, n);
      s.shadow = sh;  // the shadow step tracks Δs (vlr.shadow.step = 0)
      const Timed t = time_render(v, camera(side), s, o.warmup, o.repeats);
      csv.row("samples,{},{},{:.3f},{},{}", model_key(model, sh), n, t.median_ms, t.frame.stats.samples,
              t.frame.stats.shadow_samples);
    }
  progress("sample-count scaling done");
  // Lights: k point lights on a circle of radius 2d around the box, at height d.
  const int light_side = o.quick ? 64 : 128;
  for (auto [model, sh] : {std::pair{OpticalModel::kHG, render::ShadowMethod::kMarch},
                           std::pair{OpticalModel::kHGAttenuated, render::ShadowMethod::kMarch},
                           std::pair{OpticalModel::kHGAttenuated, render::ShadowMethod::kCache}})
    for (int k = 0; k <= 8; ++k) {
      auto s = seed_settings(model, 64);
      s.shadow = sh;
      s.lights.clear();
      for (int i = 0; i < k; ++i) {
        render::VolumeLight l;
        const double a = 2 * std::numbers::pi * i / 8;
        l.position = Vec3(600 * std::cos(a), 600 * std::sin(a), 300);
        l.intensity = render::Rgb::Constant(0.6 / std::max(1, k));
        s.lights.push_back(l);
      }
      if (k == 0) s.model = OpticalModel::kEmissionAbsorption;  // t(0): no light term at all
      const Timed t = time_render(v, camera(light_side), s, o.warmup, o.repeats);
      csv.row("lights,{},{},{:.3f},{},{}", model_key(model, sh), k, t.median_ms, t.frame.stats.samples,
              t.frame.stats.shadow_samples);
    }
  progress("light-count scaling done");
  for (int px : {128, 256, 512})
    for (auto model : {OpticalModel::kEmission, OpticalModel::kHG}) {
      const Timed t = time_render(v, camera(px), seed_settings(model, 64), o.warmup, o.repeats);
      csv.row("pixels,{},{},{:.3f},{},{}", model_key(model, render::ShadowMethod::kMarch), px * px, t.median_ms,
              t.frame.stats.samples, t.frame.stats.shadow_samples);
    }
  progress("pixel scaling done");
  csv.write(dir / "scaling.csv");
}

// ---- time against error (Pareto) ----------------------------------------------------------------

void study_pareto(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const auto v = turbulence(render::VolumeKind::kTurbulenceSphere, 64);
  const int side = o.quick ? 96 : 256;
  const auto cam = camera(side);
  auto base = [&](int n) {
    auto s = seed_settings(OpticalModel::kHGAttenuated, n);
    return s;
  };
  // The reference: n = 1024, the exact shadow march with the same small step.
  progress("Pareto: reference (n = 1024, exact shadow march)");
  const auto t_ref = std::chrono::steady_clock::now();
  const render::VolumeFrame ref = render::render_volume(v, cam, base(1024));
  const double ref_ms = ms_since(t_ref);
  const ImageF ref_img = render::composite_over(ref, render::Rgb::Zero());
  write_image(dir / "pareto_reference.png", ref_img);
  CsvTable csv("knob,value,median_ms,rel_rmse,primary_samples,shadow_samples,cache_build_ms,terminated");
  auto measure = [&](const std::string& knob, const std::string& value, const render::VolumeRenderSettings& s) {
    const Timed t = time_render(v, cam, s, o.warmup, o.repeats);
    const double err = rel_rmse(render::composite_over(t.frame, render::Rgb::Zero()), ref_img);
    csv.row("{},{},{:.3f},{:.6g},{},{},{:.3f},{}", knob, value, t.median_ms, err, t.frame.stats.samples,
            t.frame.stats.shadow_samples, t.cache_ms, t.frame.stats.terminated);
    progress(fmt::format("Pareto {} = {}: {:.1f} ms, relative RMSE {:.4f}", knob, value, t.median_ms, err));
  };
  for (int n : {16, 32, 50, 64, 100, 200, 400}) measure("samples", std::to_string(n), base(n));
  const double ds100 = render::primary_step(v, base(100));
  for (double f : {4.0, 2.0, 1.0, 0.5}) {
    auto s = base(100);
    s.shadow_step = f * ds100;
    measure("shadow_step", fmt::format("{} ds", f), s);
  }
  for (double scale : {0.25, 0.5, 1.0, 2.0}) {
    auto s = base(100);
    s.shadow = render::ShadowMethod::kCache;
    s.shadow_cache_scale = scale;
    measure("shadow_cache", fmt::format("{}", scale), s);
  }
  for (double ert : {0.0, 1e-4, 1e-3, 1e-2, 0.05}) {
    auto s = base(100);
    s.shadow = render::ShadowMethod::kCache;
    s.ert_transmittance = ert;
    measure("ert", fmt::format("{}", ert), s);
  }
  for (int n : {32, 64}) {
    for (auto off : {render::FirstOffset::kZero, render::FirstOffset::kHalf, render::FirstOffset::kJitter}) {
      auto s = base(n);
      s.shadow = render::ShadowMethod::kCache;
      s.first_offset = off;
      measure("first_offset",
              fmt::format("n{} {}", n,
                          off == render::FirstOffset::kZero   ? "zero"
                          : off == render::FirstOffset::kHalf ? "half"
                                                              : "jitter"),
              s);
    }
  }
  for (auto q : {render::Quadrature::kInclusive, render::Quadrature::kExclusive, render::Quadrature::kExponential}) {
    auto s = base(64);
    s.shadow = render::ShadowMethod::kCache;
    s.quadrature = q;
    measure("quadrature", render::quadrature_name(q), s);
  }
  csv.write(dir / "pareto.csv");
  // The shadow cache alone: T from the cache against the exact march at random points inside.
  {
    auto s = base(100);
    s.shadow = render::ShadowMethod::kCache;
    CsvTable cache_csv("cache_scale,build,points,mean_abs_error,max_abs_error,build_ms");
    for (auto build : {render::ShadowCacheBuild::kSweep, render::ShadowCacheBuild::kMarch})
      for (double scale : {0.5, 1.0, 2.0}) {
        s.shadow_cache_build = build;
        s.shadow_cache_scale = scale;
        const auto t0 = std::chrono::steady_clock::now();
        const render::ShadowCache c = render::build_shadow_cache(v, s, 0);
        const double build_ms = ms_since(t0);
        std::uint64_t h = 12345;
        double sum = 0, worst = 0;
        const int points = o.quick ? 2000 : 20000;
        for (int i = 0; i < points; ++i) {
          Vec3 p;
          for (int a = 0; a < 3; ++a) {
            h = h * 6364136223846793005ull + 1442695040888963407ull;
            p[a] = -150 + 300 * double(h >> 11) * (1.0 / 9007199254740992.0);
          }
          const double exact = render::shadow_transmittance(v, s, 0, p);
          const double cached = c.transmittance.sample(p);
          sum += std::abs(cached - exact);
          worst = std::max(worst, std::abs(cached - exact));
        }
        cache_csv.row("{},{},{},{:.6g},{:.6g},{:.3f}", scale,
                      build == render::ShadowCacheBuild::kSweep ? "sweep" : "march", points, sum / points, worst,
                      build_ms);
      }
    cache_csv.write(dir / "shadow_cache.csv");
  }
  record["pareto"] = {
      {"scene", "Box300 of turbulence_sphere 64³, HGAttenuated, point light (600, 600, 600)"},
      {"image", fmt::format("{0}x{0}", side)},
      {"reference", "n = 1024, exact shadow march with shadow step = its Δs, no ERT"},
      {"reference_ms", ref_ms},
      {"error", "relative RMS difference of the pixel colours over black: sqrt(Σ|I - I_ref|² / Σ|I_ref|²)"}};
}

// ---- OpenVDB peer ---------------------------------------------------------------------------------

void study_peer(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const int n_vol = o.quick ? 64 : 128;
  const auto v = turbulence(render::VolumeKind::kTurbulenceSphere, n_vol);
  const double voxel = v.spacing().x();
  const int side = o.quick ? 128 : 256;
  const auto cam = camera(side);
  const Vec3 to_light = Vec3(0.6, 0.6, 0.5).normalized();
  const double kappa = 0.02, albedo = 0.9, L = 1.0;
  // The same physics in meltlab's terms: HGAttenuated, isotropic (c = 0), κ in the BRDF (so the
  // in-scattered radiance is a σ p L T''), the exponential step, a directional light. OpenVDB's
  // phase is 1, not 1/4π: its image is 4π times ours.
  auto ours = [&](double step_voxels, render::ShadowMethod sh) {
    render::VolumeRenderSettings s;
    s.model = OpticalModel::kHGAttenuated;
    s.hg_c = 0.0;
    s.kappa = kappa;
    s.albedo = albedo;
    s.kappa_in_brdf = true;
    s.emission = render::Rgb::Zero();
    s.quadrature = render::Quadrature::kExponential;
    s.step_rule = render::StepRule::kFitSegment;
    s.step = step_voxels * voxel;
    s.first_offset = render::FirstOffset::kHalf;
    s.shadow_step = step_voxels * voxel;
    s.shadow = sh;
    render::VolumeLight l;
    l.type = render::LightType::kDirectional;
    l.to_light = to_light;
    l.intensity = render::Rgb::Constant(L);
    s.lights = {l};
    return s;
  };
  const double ref_step = o.quick ? 0.25 : 0.125;
  progress(fmt::format("peer: reference (steps of {} voxel, exact shadow march)", ref_step));
  const ImageF ref = render::composite_over(render::render_volume(v, cam, ours(ref_step, render::ShadowMethod::kMarch)),
                                            render::Rgb::Zero());
  write_image(dir / "peer_reference.png", ref);
  const render::OpenVdbPeer peer(v);
  CsvTable csv("renderer,step_voxels,median_ms,min_ms,rel_rmse_vs_reference,rel_diff_vs_openvdb,cache_build_ms");
  for (double step : {2.0, 1.0, 0.5}) {
    render::OpenVdbRenderSettings ps;
    ps.primary_step_voxels = ps.shadow_step_voxels = step;
    ps.extinction_per_voxel = kappa * voxel;
    ps.albedo = albedo;
    ps.to_light = to_light;
    ps.light_colour = Vec3::Constant(L);
    ps.cutoff = 1e-9;  // no early termination or density cut: the same integral as ours
    std::vector<double> ms;
    ImageF vdb;
    for (int i = 0; i < o.warmup + o.repeats; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      vdb = peer.render(cam, ps);
      if (i >= o.warmup) ms.push_back(ms_since(t0));
    }
    for (float& x : vdb.values()) x = float(double(x) / (4 * std::numbers::pi));
    csv.row("openvdb,{},{:.3f},{:.3f},{:.6g},0,0", step, median(ms), *std::min_element(ms.begin(), ms.end()),
            rel_rmse(vdb, ref));
    if (step == 1.0) write_image(dir / "peer_openvdb.png", vdb);
    for (auto sh : {render::ShadowMethod::kMarch, render::ShadowMethod::kCache}) {
      const Timed t = time_render(v, cam, ours(step, sh), o.warmup, o.repeats);
      const ImageF img = render::composite_over(t.frame, render::Rgb::Zero());
      csv.row("{},{},{:.3f},{:.3f},{:.6g},{:.6g},{:.3f}",
              sh == render::ShadowMethod::kCache ? "meltlab_cache" : "meltlab_march", step, t.median_ms, t.min_ms,
              rel_rmse(img, ref), rel_rmse(img, vdb), t.cache_ms);
      if (step == 1.0 && sh == render::ShadowMethod::kCache) write_image(dir / "peer_meltlab.png", img);
    }
    progress(fmt::format("peer: step {} voxel done", step));
  }
  csv.write(dir / "peer.csv");
  record["peer"] = {
      {"volume", fmt::format("turbulence_sphere {}³ in Box300 ({} active voxels, {} bytes as a FloatGrid)", n_vol,
                             peer.active_voxels(), peer.memory_bytes())},
      {"image", fmt::format("{0}x{0}", side)},
      {"physics",
       "single scattering of a directional light, isotropic phase, shadowed, exponential step; "
       "OpenVDB's radiance divided by 4π (its phase is 1)"},
      {"reference", fmt::format("meltlab, steps of {} voxel, exact shadow march", ref_step)},
      {"kappa", kappa},
      {"albedo", albedo}};
}

}  // namespace

void run_volume_bench(const VolumeBenchOptions& options) {
  VolumeBenchOptions o = options;
  if (o.large_size == 0) o.large_size = o.quick ? 800 : 2000;
  if (o.large_size < 16 || o.large_size > 4096) throw InputError("--large-size must be in [16, 4096]");
  o.table3_qcs = slicing_bench::table3_qcs(o);
  const std::map<std::string, std::function<void(const VolumeBenchOptions&, const fs::path&, json&)>> run{
      {"tables", study_tables},
      {"scaling", study_scaling},
      {"pareto", study_pareto},
      {"peer", study_peer},
      {"seed001-generate", clv_bench::study_generate},
      {"seed001-tables", clv_bench::study_tables},
      {"seed001-large", clv_bench::study_large},
      {"seed001-sweeps", clv_bench::study_sweeps},
      {"seed001-peer", clv_bench::study_peer},
      {"seed001-steps", clv_bench::study_steps},
      {"seed001-ess", clv_bench::study_ess},
      {"seed003-figures", slicing_bench::study_figures},
      {"seed003-table3", slicing_bench::study_table3},
      {"seed003-table4", slicing_bench::study_table4},
      {"seed003-pareto", slicing_bench::study_pareto}};
  std::map<std::string, BenchStudy> studies;
  for (const auto& [name, fn] : run)
    studies[name] = [&o, fn = fn](const fs::path& dir, json& record) { fn(o, dir, record); };
  run_bench_studies(
      BenchStudiesRun{"volume bench", o.studies, o.quick, o.warmup, o.repeats, o.out_dir, o.overwrite, o.command_line},
      studies);
}

}  // namespace meltlab::experiments
