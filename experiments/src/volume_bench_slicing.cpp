// Seed 003's studies of `meltlab volume bench` (see volume_bench_slicing.h).

#include "volume_bench_slicing.h"

#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/statistics.h>
#include <meltlab/core/time.h>
#include <meltlab/datasets/catalog.h>
#include <meltlab/experiments/csv_table.h>
#include <meltlab/experiments/volume_run.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/slicing/slicing_renderer.h>
#include <meltlab/render/slicing/slicing_scene.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/volume_scene.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::experiments::slicing_bench {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

void progress(const std::string& what) { std::fprintf(stderr, "meltlab: volume bench: %s\n", what.c_str()); }

/// One scene of --slicing-scenes, loaded: its volume, mask and settings.
struct LoadedScene {
  fs::path file;
  render::VolumeScene scene;
  render::Volume volume;
  render::SlicingSettings settings;  ///< with the scene's mask
};

LoadedScene load(const fs::path& file) {
  LoadedScene l;
  l.file = file;
  l.scene = render::read_volume_scene(file);
  if (!l.scene.slicing)
    throw InputError(fmt::format("{}: the seed003-* studies need a scene with method: slicing", file.string()));
  l.volume = render::load_scene_volume(l.scene);
  l.settings = l.scene.slicing->settings;
  try {
    l.settings.mask = render::build_scene_mask(*l.scene.slicing, l.volume.domain());
    render::check_slicing_settings(l.volume, l.settings);
  } catch (const InputError& e) {
    throw InputError(fmt::format("{}: {}", file.string(), e.what()));
  }
  const Eigen::Vector3d eye = std::get<render::Pinhole>(l.scene.camera).camera_from_world.inverse().translation();
  if (l.volume.domain().contains(eye))
    throw InputError(
        fmt::format("{}: the camera is inside the volume's box (slicing needs it outside)", file.string()));
  return l;
}

const LoadedScene& reference_scene(const VolumeBenchOptions& o) {
  static std::optional<LoadedScene> cached;
  static fs::path cached_file;
  if (o.slicing_scenes.empty())
    throw InputError("--slicing-scenes: the seed003-* studies need at least one scene (method: slicing)");
  if (!cached || cached_file != o.slicing_scenes.front()) {
    cached = load(o.slicing_scenes.front());
    cached_file = o.slicing_scenes.front();
  }
  return *cached;
}

/// The gradient volume of a scene's volume through the data cache (none if no cache is configured).
render::GradientVolume gradients_of(const render::Volume& v, const render::GradientOptions& g) {
  fs::path cache;
  try {
    cache = datasets::default_cache_dir() / "slicing-gradients";
  } catch (const InputError&) {
  }
  return render::cached_gradient_volume(v, g, cache);
}

struct Timed {
  double median_ms = 0, min_ms = 0, max_ms = 0, render_ms = 0, post_ms = 0;
  double cpu_ms = 0;  ///< median process CPU time per frame (all threads): steadier than wall time under load
  render::SlicingFrame frame;
};

/// Frames of several renderers, interleaved (warm-up rounds first, then `repeats` timed rounds of
/// one frame each), so that a change of the machine's load falls on all of them alike.
std::vector<Timed> time_interleaved(const std::vector<const render::SlicingRenderer*>& renderers,
                                    const render::Camera& cam, int warmup, int repeats) {
  const std::size_t n = renderers.size();
  std::vector<std::vector<double>> ms(n), rms(n), pms(n), cpu(n);
  std::vector<Timed> t(n);
  for (int i = 0; i < warmup + repeats; ++i)
    for (std::size_t k = 0; k < n; ++k) {
      const double c0 = process_cpu_ms();
      const auto t0 = std::chrono::steady_clock::now();
      renderers[k]->render_into(cam, t[k].frame);  // the last frame's images reused, as a frame loop does
      const double d = ms_since(t0);
      const double c = process_cpu_ms() - c0;
      if (i < warmup) continue;
      ms[k].push_back(d), rms[k].push_back(t[k].frame.stats.render_ms), pms[k].push_back(t[k].frame.stats.post_ms);
      cpu[k].push_back(c);
    }
  for (std::size_t k = 0; k < n; ++k) {
    t[k].median_ms = median(ms[k]);
    t[k].min_ms = *std::min_element(ms[k].begin(), ms[k].end());
    t[k].max_ms = *std::max_element(ms[k].begin(), ms[k].end());
    t[k].render_ms = median(rms[k]);
    t[k].post_ms = median(pms[k]);
    t[k].cpu_ms = median(cpu[k]);
  }
  return t;
}

Timed time_frames(const render::SlicingRenderer& r, const render::Camera& cam, int warmup, int repeats) {
  return time_interleaved({&r}, cam, warmup, repeats).front();
}

/// The share of pixels whose accumulated opacity exceeds 0.01 (the object's coverage of the image).
double coverage(const ImageF& alpha) {
  std::size_t n = 0;
  for (float a : alpha.values()) n += a > 0.01f;
  return double(n) / double(alpha.size());
}

/// Root-mean-square difference of two images' values (same size and channels).
double rmse(const ImageF& a, const ImageF& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += std::pow(double(a.values()[i]) - double(b.values()[i]), 2);
  return std::sqrt(s / double(a.size()));
}

ImageF clamped(const ImageF& img, double exposure) {
  ImageF out(img.width(), img.height(), 3);
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = std::clamp(float(exposure) * img.at(x, y, c), 0.0f, 1.0f);
  return out;
}

/// Quick mode: the camera at half the scene's width and height (the same framing); full: as is.
render::Camera quick_camera(const VolumeBenchOptions& o, const render::Camera& c) {
  const auto& p = std::get<render::Pinhole>(c);
  return o.quick ? resized_camera(c, std::max(1, p.width / 2), std::max(1, p.height / 2)) : c;
}

std::string size_text(const render::Camera& c) {
  const auto& p = std::get<render::Pinhole>(c);
  return fmt::format("{}x{}", p.width, p.height);
}

const render::SlicingMode kModes[] = {render::SlicingMode::kBlend, render::SlicingMode::kMip,
                                      render::SlicingMode::kCombined};

}  // namespace

// ---- figures -------------------------------------------------------------------------------------

void study_figures(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  if (o.slicing_scenes.empty())
    throw InputError("--slicing-scenes: the seed003-* studies need at least one scene (method: slicing)");
  fs::create_directories(dir / "slicing_figures");
  CsvTable csv("scene,mode,width,height,frame_ms,render_ms,post_ms,samples,samples_past_mask,coverage,png,png_bloom");
  json scenes = json::array();
  for (const auto& file : o.slicing_scenes) {
    const LoadedScene l = load(file);
    // Quick mode: half the scene's image size (the same framing).
    const render::Camera cam = quick_camera(o, l.scene.camera);
    const std::string stem = file.stem().string();
    const auto grads = gradients_of(l.volume, l.settings.gradient);
    for (const auto mode : kModes) {
      render::SlicingSettings s = l.settings;
      s.mode = mode;
      s.post.enabled = true;  // raw = the frame without bloom (the colour adjustment is the identity)
      const render::SlicingRenderer r(l.volume, s, grads);
      const Timed t = time_frames(r, cam, 0, 1);
      const std::string name = fmt::format("{}_{}", stem, render::slicing_mode_name(mode));
      write_image(dir / "slicing_figures" / (name + ".png"), clamped(t.frame.raw, l.scene.exposure));
      write_image(dir / "slicing_figures" / (name + "_bloom.png"), clamped(t.frame.rgb, l.scene.exposure));
      csv.row("{},{},{},{},{:.3f},{:.3f},{:.3f},{},{},{:.4f},slicing_figures/{}.png,slicing_figures/{}_bloom.png", stem,
              render::slicing_mode_name(mode), t.frame.rgb.width(), t.frame.rgb.height(), t.median_ms, t.render_ms,
              t.post_ms, t.frame.stats.samples, t.frame.stats.classified, coverage(t.frame.alpha), name, name);
      progress(fmt::format("seed003 figure {}: {:.0f} ms", name, t.median_ms));
    }
    json mask = json::array();
    for (const auto& e : l.scene.slicing->mask_edits)
      mask.push_back({{"shape", render::mask_shape_name(e.shape)},
                      {"centre", {e.centre.x(), e.centre.y(), e.centre.z()}},
                      {"half_size", {e.half_size.x(), e.half_size.y(), e.half_size.z()}},
                      {"index", e.index}});
    scenes.push_back({{"file", file.string()}, {"stem", stem}, {"mask_edits", mask}});
  }
  csv.write(dir / "slicing_figures.csv");
  record["seed003_figures"] = {{"scenes", scenes},
                               {"image", o.quick ? "half the scene's size (quick)" : "the scene's size"},
                               {"bloom", "without: the frame before the post chain; with: the chain of bloom.h"}};
}

// ---- Table 3: time against QC, Blend and combined ---------------------------------------------------

std::vector<double> table3_qcs(const VolumeBenchOptions& o) {
  std::vector<double> qcs = o.table3_qcs;
  // The source's Table 3 grid (its 13 QCs, so each row sits beside the source's and the fit spans the
  // same 1/QC range; ~15 s a repeat here); full mode adds QC 8, past the source's range.
  if (qcs.empty()) {
    qcs = {0.2, 0.4, 0.8, 1, 1.5, 2, 2.5, 3, 3.5, 4, 5, 6, 7};
    if (!o.quick) qcs.push_back(8);
  }
  for (double qc : qcs)
    if (!(qc >= 0.01 && qc <= 1000))
      throw InputError(fmt::format("--qcs: quality class {} is outside [0.01, 1000] (the renderer's range)", qc));
  std::sort(qcs.begin(), qcs.end());
  if (std::adjacent_find(qcs.begin(), qcs.end()) != qcs.end())
    throw InputError("--qcs: a quality class is given twice");
  return qcs;
}

void study_table3(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const LoadedScene& l = reference_scene(o);
  const std::vector<double>& qcs = o.table3_qcs;  // resolved by table3_qcs() in run_volume_bench()
  const auto grads = gradients_of(l.volume, l.settings.gradient);
  CsvTable csv(
      "mode,qc,width,height,median_ms,min_ms,max_ms,cpu_ms,render_ms,post_ms,fps,samples,samples_past_mask,"
      "skipped_empty,slices,slice_spacing,coverage");
  double cover = 0;
  // The source's fps are a running frame loop's: at least one untimed frame per renderer first (its
  // first frame touches the frame's images, ~26 MB at 1000 x 730, and the volume for the first time),
  // also where --warmup=0 (quick mode) saves the other studies that frame.
  const int table3_warmup = std::max(o.warmup, 1);
  for (double qc : qcs) {
    // Blend and combined at this QC, their frames interleaved (a load change hits both).
    std::vector<render::SlicingSettings> settings;
    for (const auto mode : {render::SlicingMode::kBlend, render::SlicingMode::kCombined}) {
      render::SlicingSettings s = l.settings;
      s.mode = mode;
      s.quality_class = qc;
      s.post.enabled = false;  // the source's Table 3 is the renderer alone
      settings.push_back(s);
    }
    const render::SlicingRenderer r_blend(l.volume, settings[0], grads), r_comb(l.volume, settings[1], grads);
    const auto times = time_interleaved({&r_blend, &r_comb}, l.scene.camera, table3_warmup, o.repeats);
    for (std::size_t k = 0; k < 2; ++k) {
      const Timed& t = times[k];
      const double c = coverage(t.frame.alpha);
      if (k == 0 && qc == 1) cover = c;
      const auto& st = t.frame.stats;
      const std::string mode = render::slicing_mode_name(settings[k].mode);
      csv.row("{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.4f},{},{},{},{},{:.6g},{:.4f}", mode, qc,
              t.frame.rgb.width(), t.frame.rgb.height(), t.median_ms, t.min_ms, t.max_ms, t.cpu_ms, t.render_ms,
              t.post_ms, 1000.0 / t.median_ms, st.samples, st.classified, st.skipped, st.slices, st.slice_spacing, c);
      progress(fmt::format("seed003 Table 3 {} QC {}: {:.1f} ms (CPU {:.1f} ms)", mode, qc, t.median_ms, t.cpu_ms));
    }
  }
  csv.write(dir / "slicing_table3.csv");
  record["seed003_table3"] = {{"scene", l.file.string()},
                              {"image", size_text(l.scene.camera)},
                              {"coverage_blend_qc1", cover},
                              {"coverage_rule", "share of pixels with accumulated alpha > 0.01"},
                              {"bloom", false},
                              {"warmup_frames", table3_warmup},
                              {"qcs", qcs}};
}

// ---- Table 4: time per sample against data size ------------------------------------------------------

namespace {

std::array<int, 3> parse_dims(const std::string& text) {
  std::array<int, 3> d{0, 0, 0};
  int n = 0;
  if (std::sscanf(text.c_str(), "%dx%dx%d%n", &d[0], &d[1], &d[2], &n) != 3 || n != int(text.size()) ||
      *std::min_element(d.begin(), d.end()) < 2 || *std::max_element(d.begin(), d.end()) > 2048)
    throw InputError(fmt::format("--sizes: '{}' is not NXxNYxNZ with each in [2, 2048]", text));
  return d;
}

}  // namespace

void study_table4(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const LoadedScene& l = reference_scene(o);
  const render::Camera cam = quick_camera(o, l.scene.camera);
  std::vector<std::string> sizes = o.table4_sizes;
  if (sizes.empty()) {
    // The source's sizes (its 1³ texture is 2³ here: node samples need two per axis); full mode
    // adds one beyond this machine's last-level cache.
    sizes = {"2x2x2", "50x50x50", "100x100x100", "150x150x100", "200x200x100", "256x256x113"};
    if (!o.quick) sizes.push_back("512x512x226");
  }
  std::vector<std::array<int, 3>> dims;
  for (const auto& s : sizes) dims.push_back(parse_dims(s));
  const render::Box3 box = l.volume.domain();
  // A constant slice spacing in scene units: 3 of the reference volume's smallest voxel, at least
  // what QC >= 0.01 allows on the coarsest volume (so every size gets the same planes).
  double dd = 3 * l.volume.spacing().minCoeff();
  for (const auto& d : dims)
    for (int a = 0; a < 3; ++a) dd = std::max(dd, 0.0101 * (box.hi[a] - box.lo[a]) / (d[a] - 1));
  // A TF visible at every value (α 0.01 .. 0.05): every sample is fetched, classified and composited.
  std::array<render::TfCurve, 4> curves;
  curves[0].points = {{0.0, 0.8}, {1.0, 1.0}};
  curves[1].points = {{0.0, 0.8}, {1.0, 0.9}};
  curves[2].points = {{0.0, 0.8}, {1.0, 0.8}};
  curves[3].points = {{0.0, 0.01}, {1.0, 0.05}};
  const auto tf = render::TransferFunction::piecewise_linear(curves, "visible_everywhere");
  CsvTable csv(
      "dims,voxels,data_bytes,qc,slice_spacing,slices,median_ms,min_ms,max_ms,cpu_ms,render_ms,samples,ns_per_sample,"
      "cpu_ns_per_sample,generate_ms");
  for (std::size_t i = 0; i < dims.size(); ++i) {
    const auto& d = dims[i];
    render::VolumeGenerateOptions g;
    g.kind = render::VolumeKind::kCtPhantom;
    g.nx = d[0], g.ny = d[1], g.nz = d[2];
    const auto t_gen = std::chrono::steady_clock::now();
    render::Volume v = render::generate_volume(g);
    v.fit_to_box(box);
    const double gen_ms = ms_since(t_gen);
    render::SlicingSettings s;
    s.mode = render::SlicingMode::kBlend;
    s.tfs[0] = tf;
    s.value_range = std::make_pair(0.0, 1.0);
    s.skip_empty = false;
    s.quality_class = dd / v.spacing().minCoeff();
    const render::SlicingRenderer r(v, s);
    const Timed t = time_frames(r, cam, o.warmup, o.repeats);
    const auto& st = t.frame.stats;
    const std::int64_t voxels = std::int64_t(d[0]) * d[1] * d[2];
    const double n = double(std::max<std::int64_t>(1, st.samples));
    csv.row("{},{},{},{:.6g},{:.6g},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{},{:.4f},{:.4f},{:.1f}", sizes[i], voxels,
            voxels * std::int64_t(sizeof(float)), s.quality_class, st.slice_spacing, st.slices, t.median_ms, t.min_ms,
            t.max_ms, t.cpu_ms, t.render_ms, st.samples, 1e6 * t.render_ms / n, 1e6 * t.cpu_ms / n, gen_ms);
    progress(fmt::format("seed003 Table 4 {}: {:.1f} ms, {:.2f} ns/sample", sizes[i], t.render_ms,
                         1e6 * t.render_ms / double(std::max<std::int64_t>(1, st.samples))));
  }
  csv.write(dir / "slicing_table4.csv");
  record["seed003_table4"] = {
      {"scene", l.file.string()},
      {"image", size_text(cam)},
      {"slice_spacing", dd},
      {"volumes", "the CT phantom generated at each size, normalised, placed in the reference scene's box; float32"},
      {"settings", "Blend over, no mask, one TF visible at every value, empty-space skipping off, no bloom"},
      {"ns_per_sample",
       "render_ms (the renderer's own time, without the post chain) / samples, wall time on all threads"},
      {"caches", "provenance.hardware.caches (sysfs of cpu0)"}};
}

// ---- slicing against ray casting; mask and bloom costs ---------------------------------------------

void study_pareto(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const LoadedScene& l = reference_scene(o);
  const render::Camera cam = quick_camera(o, l.scene.camera);
  const double h0 = l.volume.spacing().minCoeff();
  // One piecewise-constant TF for both (the ray caster's TF model reads that kind only): a faint
  // skin at the fat value, a translucent bone; in the normalised values of the scene's volume.
  std::vector<render::TfRange> ranges(2);
  ranges[0] = {0.42, 0.47, false, true, Eigen::Vector3d(240, 190, 165), 0.02};
  ranges[1] = {0.70, 1.00, false, true, Eigen::Vector3d(255, 245, 225), 0.08};
  const render::TransferFunction tf(ranges, "skin_bone");
  auto ray_caster = [&](double step) {
    render::VolumeRenderSettings rc;
    rc.model = render::OpticalModel::kTransferFunction;
    rc.tf.table = tf;
    rc.tf.shading.enabled = false;
    rc.step_rule = render::StepRule::kFixedStep;
    rc.step = step;
    rc.ert_transmittance = 0;
    rc.skip_empty = true;  // exact: the same image
    return rc;
  };
  auto rgb_of = [](const ImageF& radiance) {
    ImageF out(radiance.width(), radiance.height(), 3);
    for (int y = 0; y < out.height(); ++y)
      for (int x = 0; x < out.width(); ++x)
        for (int c = 0; c < 3; ++c) out.at(x, y, c) = radiance.at(x, y, c);
    return out;
  };
  const double ref_div = o.quick ? 8 : 16;
  progress(fmt::format("seed003 Pareto: reference (ray caster, step h0/{})", ref_div));
  const auto t_ref = std::chrono::steady_clock::now();
  const ImageF ref = rgb_of(render::render_volume(l.volume, cam, ray_caster(h0 / ref_div)).radiance);
  const double ref_ms = ms_since(t_ref);
  double ref_rms = 0;
  for (float x : ref.values()) ref_rms += double(x) * double(x);
  ref_rms = std::sqrt(ref_rms / double(ref.size()));
  write_image(dir / "slicing_pareto_reference.png", clamped(ref, 1));
  // samples: the plane (slicing) or ray (ray caster) positions; fetched: those whose value was read
  // (both skip empty space exactly: slicing 8³-voxel cells, the ray caster its multi-level index).
  CsvTable csv("method,qc,step,median_ms,min_ms,max_ms,cpu_ms,samples,fetched,rmse,rel_rmse");
  const std::vector<double> qcs = o.quick ? std::vector<double>{0.5, 1, 2, 4} : std::vector<double>{0.25, 0.5, 1, 2, 4};
  for (double qc : qcs) {
    render::SlicingSettings s;
    s.mode = render::SlicingMode::kBlend;
    s.tfs[0] = tf;
    s.value_range = std::make_pair(0.0, 1.0);  // the volume's values, as the ray caster reads them
    s.quality_class = qc;
    const render::SlicingRenderer r(l.volume, s);
    const Timed t = time_frames(r, cam, o.warmup, o.repeats);
    const double e = rmse(t.frame.raw, ref);
    csv.row("slicing,{},{:.6g},{:.3f},{:.3f},{:.3f},{:.3f},{},{},{:.6g},{:.6g}", qc, qc * h0, t.median_ms, t.min_ms,
            t.max_ms, t.cpu_ms, t.frame.stats.samples, t.frame.stats.samples - t.frame.stats.skipped, e, e / ref_rms);
    if (qc == 1) write_image(dir / "slicing_pareto_qc1.png", clamped(t.frame.raw, 1));
    const render::VolumeTracer tracer(l.volume, ray_caster(qc * h0));
    std::vector<double> ms, cpu;
    render::VolumeFrame f;
    for (int i = 0; i < o.warmup + o.repeats; ++i) {
      const double c0 = process_cpu_ms();
      const auto t0 = std::chrono::steady_clock::now();
      f = tracer.render(cam);
      if (i >= o.warmup) ms.push_back(ms_since(t0)), cpu.push_back(process_cpu_ms() - c0);
    }
    const double er = rmse(rgb_of(f.radiance), ref);
    csv.row("ray_casting,{},{:.6g},{:.3f},{:.3f},{:.3f},{:.3f},{},{},{:.6g},{:.6g}", qc, qc * h0, median(ms),
            *std::min_element(ms.begin(), ms.end()), *std::max_element(ms.begin(), ms.end()), median(cpu),
            f.stats.samples + f.stats.skipped, f.stats.samples, er, er / ref_rms);
    progress(fmt::format("seed003 Pareto QC {}: slicing {:.1f} ms RMSE {:.5f}, ray casting {:.1f} ms RMSE {:.5f}", qc,
                         t.median_ms, e, median(ms), er));
  }
  csv.write(dir / "slicing_pareto.csv");

  // Costs: the mask lookup (none against an all-ones mask at the scene's mask resolution: the same
  // image) and bloom (off against on), Blend at QC 1 with the scene's TFs, interleaved repeats.
  const int repeats = std::max(3, o.repeats);
  const auto& sl = *l.scene.slicing;
  render::SlicingSettings base = l.settings;
  base.mode = render::SlicingMode::kBlend;
  base.quality_class = 1;
  base.post.enabled = false;
  base.mask = render::MaskVolume();
  render::SlicingSettings masked = base;
  masked.mask = render::MaskVolume(sl.mask_resolution, l.volume.domain(), 1);
  render::SlicingSettings bloom = base;
  bloom.post.enabled = true;
  const render::SlicingRenderer r_base(l.volume, base), r_mask(l.volume, masked), r_bloom(l.volume, bloom);
  const auto times = time_interleaved({&r_base, &r_mask, &r_bloom}, cam, o.warmup, repeats);
  const Timed &t_base = times[0], &t_mask = times[1], &t_bloom = times[2];
  const bool same_image = t_base.frame.raw.values() == t_mask.frame.raw.values();
  CsvTable costs("knob,state,frame_ms,cpu_ms,render_ms,post_ms,repeats,samples,same_image_as_off");
  for (auto [knob, state, t] : {std::tuple{"mask", "off", &t_base}, std::tuple{"mask", "all_ones", &t_mask},
                                std::tuple{"bloom", "off", &t_base}, std::tuple{"bloom", "on", &t_bloom}}) {
    const bool same = std::string(knob) == "mask" ? same_image : std::string(state) == "off";
    costs.row("{},{},{:.3f},{:.3f},{:.3f},{:.3f},{},{},{}", knob, state, t->median_ms, t->cpu_ms, t->render_ms,
              t->post_ms, repeats, t->frame.stats.samples, same ? "yes" : "no");
  }
  costs.write(dir / "slicing_costs.csv");
  progress(fmt::format("seed003 costs: CPU {:.1f} ms, with mask {:.1f} ms, with bloom {:.1f} ms (post {:.1f} ms)",
                       t_base.cpu_ms, t_mask.cpu_ms, t_bloom.cpu_ms, t_bloom.post_ms));
  record["seed003_pareto"] = {
      {"scene", l.file.string()},
      {"image", size_text(cam)},
      {"tf", "piecewise constant: (0.42, 0.47] skin (240, 190, 165) α 0.02; (0.70, 1.00] bone (255, 245, 225) α 0.08"},
      {"reference", fmt::format("the ray caster's TF model, fixed step h0/{}, no shading, no ERT", ref_div)},
      {"reference_ms", ref_ms},
      {"reference_rms", ref_rms},
      {"equal_density", "slicing plane spacing QC·h0 against the ray caster's fixed step QC·h0"},
      {"error", "RMSE of the RGB values over black; rel_rmse = RMSE / RMS of the reference"},
      {"costs",
       fmt::format("Blend QC 1 with the scene's TFs at {}, medians of {} interleaved repeats (wall and process CPU "
                   "time); mask: an "
                   "all-ones {}x{}x{} mask against none",
                   size_text(cam), repeats, sl.mask_resolution[0], sl.mask_resolution[1], sl.mask_resolution[2])}};
}

}  // namespace meltlab::experiments::slicing_bench
