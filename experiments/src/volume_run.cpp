// `meltlab volume generate | render | info` (see volume_run.h).

#include <meltlab/core/time.h>
#include <meltlab/core/statistics.h>
#include <meltlab/experiments/volume_run.h>

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/experiments/render_json.h>
#include <meltlab/datasets/catalog.h>
#include <meltlab/render/slicing/slicing_scene.h>
#include <meltlab/render/volume/volume_io.h>
#include <meltlab/render/volume/volume_scene.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <functional>
#include <memory>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json volume_json(const render::Volume& v) {
  const render::Box3 d = v.domain();
  const auto range = v.value_range();
  return {{"dims", {v.nx(), v.ny(), v.nz()}},
          {"sample_type", render::sample_type_name(v.type())},
          {"placement", v.placement() == render::SamplePlacement::kNodes ? "nodes" : "cell_centred"},
          {"domain", {{"lo", {d.lo.x(), d.lo.y(), d.lo.z()}}, {"hi", {d.hi.x(), d.hi.y(), d.hi.z()}}}},
          {"spacing", {v.spacing().x(), v.spacing().y(), v.spacing().z()}},
          {"value_range", {static_cast<double>(range[0]), static_cast<double>(range[1])}},
          {"content_hash", render::volume_content_hash(v)}};
}

std::map<std::string, std::string> generator_record(const render::VolumeGenerateOptions& g) {
  if (g.kind == render::VolumeKind::kShapes)
    return {{"kind", "shapes"},
            {"shapes", std::to_string(g.shapes.count)},
            {"sample", std::to_string(g.shapes.sample)},
            {"object_size", std::to_string(g.shapes.object_size)},
            {"seed", std::to_string(g.shapes.seed)},
            {"rng", "xoshiro256** (splitmix64 seeding)"}};
  if (g.kind == render::VolumeKind::kSkull) return {{"kind", "skull"}, {"seed", std::to_string(g.shapes.seed)}};
  if (g.kind == render::VolumeKind::kCtPhantom) {
    render::CtPhantomOptions ct = g.ct;
    ct.dims = {g.nx, g.ny, g.nz};
    return render::describe_ct_phantom(ct);
  }
  const auto& n = g.noise;
  return {{"kind", render::volume_kind_name(g.kind)},
          {"octaves", std::to_string(n.octaves)},
          {"gain", fmt::format("{:.17g}", n.gain)},
          {"lacunarity", fmt::format("{:.17g}", n.lacunarity)},
          {"base_frequency", fmt::format("{:.17g}", n.base_frequency)},
          {"clip", n.clip == render::NoiseClip::kPerOctave ? "per_octave"
                   : n.clip == render::NoiseClip::kSumOnly ? "sum_only"
                                                           : "none"},
          {"seed", std::to_string(n.seed)},
          {"falloff", g.falloff == render::SphereFalloff::kLinear ? "linear" : "none"},
          {"constant", fmt::format("{:.17g}", g.constant)},
          {"permutation", "Perlin 2002 reference"}};
}

/// The scene's volume for a renderer of linear volumes, with what its load did (the normalisation of
/// a .vlb/.nrrd file); a blocked volume is refused, naming it.
render::SceneVolume load_linear_scene_volume(const render::VolumeScene& scene) {
  render::SceneVolume loaded = render::load_scene_volumes(scene);
  if (loaded.is_bricked()) (void)render::load_scene_volume(scene);  // throws the refusal
  return loaded;
}

/// Seed 003's data choices of a render of a .vlb/.nrrd file (`prefix`data.*); empty otherwise.
json vsi_data_json(const render::VolumeScene& scene, const std::optional<render::Normalisation>& n,
                   const std::string& prefix = "") {
  json j = json::object();
  if (!n) return j;
  j[prefix + "data.norm_source"] = render::norm_source_name(n->source);
  j[prefix + "data.norm_range"] = {n->lo, n->hi};
  j[prefix + "data.scanned_range"] = {n->scanned_min, n->scanned_max};
  j[prefix + "data.constant"] = n->constant;
  j[prefix + "data.clipped"] = {n->clipped_low, n->clipped_high};
  j[prefix + "data.window_units"] =
      scene.volume.read.window_units == render::VlbWindowUnits::kValue ? "value" : "fraction";
  j[prefix + "data.internal_bits"] = "float32";
  return j;
}

/// A describe_* list (seed settings by name) as one JSON object.
json pairs_json(const std::vector<std::pair<std::string, std::string>>& pairs) {
  json j = json::object();
  for (const auto& [k, v] : pairs) j[k] = v;
  return j;
}

/// The head of a transfer-function render's run.json: the scene file, the optical model, the
/// seed's settings under `key` (clv, vlr), and seed 003's data choices where the data has them.
json tf_run_head(const fs::path& scene_file, const render::VolumeScene& scene, const char* key,
                 const std::vector<std::pair<std::string, std::string>>& settings,
                 const std::optional<render::Normalisation>& normalisation) {
  json j;
  j["scene_file"] = scene_file.string();
  j["model"] = render::optical_model_name(scene.settings.model);
  j[key] = pairs_json(settings);
  if (const json vsi = vsi_data_json(scene, normalisation); !vsi.empty()) j["vsi"] = vsi;
  return j;
}

/// volume_json of a dense volume with where the scene got it (its generator or its file).
json scene_volume_json(const render::VolumeScene& scene, const render::Volume& volume) {
  json j = volume_json(volume);
  if (scene.volume.generate) j["generator"] = generator_record(*scene.volume.generate);
  if (!scene.volume.file.empty()) j["file"] = scene.volume.file.string();
  return j;
}

std::string order_name(render::ClvOrder o) { return o == render::ClvOrder::kBlocked ? "blocked" : "linear"; }

json clv_header_json(const render::ClvHeader& h) {
  return {{"dims", {h.dims[0], h.dims[1], h.dims[2]}},
          {"order", order_name(h.order)},
          {"block_side", h.block_side},
          {"cell_shape", {h.cell_shape[0], h.cell_shape[1], h.cell_shape[2]}},
          {"sample_type", "uint8"},
          {"placement", "nodes"},
          {"file_bytes", h.file_bytes()},
          {"sample_bytes", h.sample_bytes()}};
}

/// Occupancy and the fraction visible under the shapes TF from a value histogram (seed 001's
/// statistics in place of bit equality with the source's RNG).
json histogram_stats(const std::vector<std::int64_t>& h) {
  if (h.empty()) return nullptr;
  std::int64_t total = 0, nonzero = 0, visible = 0;
  const auto tf = render::TransferFunction::shapes();
  for (int v = 0; v < 256; ++v) {
    total += h[std::size_t(v)];
    if (v) nonzero += h[std::size_t(v)];
    if (tf.visible_at(v)) visible += h[std::size_t(v)];
  }
  return {{"voxels", total},
          {"occupancy", total ? double(nonzero) / double(total) : 0.0},
          {"fraction_visible_shapes_tf", total ? double(visible) / double(total) : 0.0}};
}

/// Prints "meltlab: volume generate: 45 % (230 of 512 MB)" every 5 %.
std::function<void(std::int64_t, std::int64_t)> progress_printer(const fs::path& out) {
  auto last = std::make_shared<int>(-1);
  return [last, out](std::int64_t done, std::int64_t total) {
    const int pct = total ? int(100 * done / total) : 100;
    if (pct / 5 == *last / 5 && pct != 100) return;
    if (pct == *last) return;
    *last = pct;
    std::fprintf(stderr, "meltlab: volume generate: %s %3d %% (%.0f of %.0f MB)\n", out.filename().c_str(), pct,
                 double(done) / 1e6, double(total) / 1e6);
  };
}

json generate_clv(const VolumeGenerateRunOptions& o) {
  if (o.box) throw InputError("--box: a .clv volume has unit spacing from the origin (its cell shape is not applied)");
  const auto& g = o.generate;
  const std::array<int, 3> dims{g.nx, g.ny, g.nz};
  render::ClvWriteOptions w;
  w.order = o.order;
  w.block_side = o.block_side;
  w.batch = o.batch;
  w.parallel = o.batch > 1;
  if (o.progress) w.progress = progress_printer(o.out);
  render::ClvWriteStats stats;
  if (g.kind == render::VolumeKind::kShapes || g.kind == render::VolumeKind::kSkull) {
    // Streamed: the samples are never all in memory.
    std::unique_ptr<render::VoxelSource> source;
    if (g.kind == render::VolumeKind::kShapes) {
      render::ShapesOptions so = g.shapes;
      so.dims = dims;
      source = std::make_unique<render::ShapesVolume>(so);
    } else {
      source = std::make_unique<render::SkullPhantom>(dims, g.shapes.seed);
    }
    stats = render::write_clv_generated(o.out, dims, *source, w);
  } else {
    if (g.storage != render::SampleType::kUint8)
      throw InputError("--out *.clv: a .clv file holds 8-bit samples (use --quantization uint8)");
    const render::Volume v = render::generate_volume(g);
    stats = render::write_clv_generated(o.out, dims, *render::voxels_of(v), w);
  }
  json j = clv_header_json(render::read_clv_header(o.out));
  j["file"] = o.out.string();
  j["generator"] = generator_record(g);
  j["write"] = {
      {"seconds", stats.seconds},
      {"batch", o.batch},
      {"parallel", w.parallel},
      {"batches", stats.batches},
      {"samples_per_second", stats.seconds > 0 ? double(j["sample_bytes"].get<std::int64_t>()) / stats.seconds : 0.0}};
  j["statistics"] = histogram_stats(stats.histogram);
  return j;
}

}  // namespace

json volume_info(const fs::path& file) {
  if (file.extension() == ".clv") {
    json j = clv_header_json(render::read_clv_header(file));
    j["file"] = file.string();
    return j;
  }
  render::VolumeReadInfo info;
  const render::Volume v = render::read_volume(file, {}, &info);
  json j = volume_json(v);
  j["file"] = file.string();
  j["format"] = info.format;
  if (render::is_medical_volume_file(file)) {
    // The stored samples (before normalisation) and what the default load did.
    j["stored"] = {{"sample_type", info.stored_type}, {"content_hash", info.samples_hash}};
    if (info.normalisation)
      j["normalisation"] = {{"norm_source", render::norm_source_name(info.normalisation->source)},
                            {"range", {info.normalisation->lo, info.normalisation->hi}},
                            {"scanned", {info.normalisation->scanned_min, info.normalisation->scanned_max}},
                            {"constant", info.normalisation->constant}};
    if (info.vlb)
      j["vlb"] = {{"version", info.vlb->version},
                  {"endian", info.vlb->endian == std::endian::big ? "big" : "little"},
                  {"range", {info.vlb->min, info.vlb->max}},
                  {"window", {info.vlb->window_lo, info.vlb->window_hi}}};
  }
  return j;
}

json run_volume_generate(const VolumeGenerateRunOptions& o) {
  const std::string ext = o.out.extension().string();
  if (ext != ".json" && ext != ".vdb" && ext != ".clv" && !render::is_medical_volume_file(o.out))
    throw InputError(
        fmt::format("--out {}: name the header NAME.json (raw samples in NAME.raw), NAME.vdb, NAME.clv (seed 001's "
                    "format), NAME.vlb, NAME.nrrd or NAME.nhdr (seed 003's)",
                    o.out.string()));
  fs::path raw = o.out;
  raw.replace_extension(".raw");
  for (const fs::path& f : {o.out, raw}) {
    std::error_code ec;
    if (fs::is_directory(f, ec)) throw InputError(fmt::format("--out {}: is a folder", f.string()));
    if (fs::exists(f, ec) && !o.overwrite && (f == o.out || ext == ".json" || ext == ".nhdr"))
      throw InputError(fmt::format("--out {}: exists (use --overwrite to replace it)", f.string()));
  }
  if (o.out.has_parent_path()) create_output_directories(o.out.parent_path(), "--out");
  if (ext == ".clv") return generate_clv(o);
  if (render::is_medical_volume_file(o.out)) {
    if (o.box) throw InputError("--box: .vlb and .nrrd volumes are placed by their spacing from the origin");
    if (o.generate.kind == render::VolumeKind::kShapes || o.generate.kind == render::VolumeKind::kSkull)
      throw InputError(fmt::format("--out {}: seed 001's volumes are written as .clv files", o.out.string()));
    if (o.generate.kind == render::VolumeKind::kCtPhantom) {
      // The phantom's int16 Hounsfield units, as the source's CT head.
      render::CtPhantomOptions ct = o.generate.ct;
      ct.dims = {o.generate.nx, o.generate.ny, o.generate.nz};
      render::write_medical_volume(o.out, render::generate_ct_phantom(ct));
    } else {
      render::write_medical_volume(o.out, render::scalar_volume_of(render::generate_volume(o.generate)));
    }
    json j = volume_info(o.out);
    j["generator"] = generator_record(o.generate);
    return j;
  }
  render::Volume v = render::generate_volume(o.generate);
  if (o.box) v.fit_to_box(*o.box);
  render::write_volume(o.out, v, generator_record(o.generate));
  json j = volume_json(v);
  j["file"] = o.out.string();
  j["generator"] = generator_record(o.generate);
  return j;
}

namespace {

/// Runs `call`; an InputError that does not name the scene file yet is re-thrown naming it.
template <class Call>
void run_naming_scene(const std::string& scene_name, const Call& call) {
  try {
    call();
  } catch (const InputError& e) {
    const std::string what = e.what();
    if (what.rfind(scene_name, 0) == 0) throw;
    throw InputError(fmt::format("{}: {}", scene_name, what));
  }
}

/// A pinhole eye inside the volume's box is refused unless the scene lets rays start at the eye
/// (vlr.camera.inside).
void check_eye_outside(const render::VolumeScene& scene, const render::Box3& domain, const std::string& scene_name) {
  const auto* pin = std::get_if<render::Pinhole>(&scene.camera);
  if (!pin || scene.settings.camera_inside != render::CameraInside::kReject) return;
  if (domain.contains(pin->camera_from_world.inverse().translation()))
    throw InputError(
        fmt::format("{}: the camera is inside the volume's box (vlr.camera.inside: reject); move it "
                    "out or set rays: {{camera_inside: start_at_eye}}",
                    scene_name));
}

/// Seed 001's transfer-function model: the volume in its layout, the empty-space index built once
/// (timed apart), then warm-up and timed frames through one tracer.
VolumeRenderRunResult run_tf_render(const VolumeRenderRunOptions& o, render::VolumeScene& scene) {
  const std::string scene_name = o.scene_file.string();
  auto named = [&](const auto& call) { run_naming_scene(scene_name, call); };
  scene.settings.record_sample_counts = o.sample_counts;
  const auto t_load = std::chrono::steady_clock::now();
  const render::SceneVolume volume = render::load_scene_volumes(scene);
  const double load_ms = ms_since(t_load);
  check_eye_outside(scene, volume.domain(), scene_name);
  std::unique_ptr<render::VolumeTracer> tracer;
  named([&] {
    if (volume.is_bricked())
      render::check_volume_render_settings(volume.bricked, scene.settings);
    else
      render::check_volume_render_settings(volume.dense, scene.settings);
  });
  RunFolder folder(o.out_dir, RunFolderOptions{"--out", "render.json", "volume render", o.overwrite});
  Provenance provenance = start_provenance("volume render", o.command_line);
  const fs::path dir = folder.path();
  named([&] {
    tracer = volume.is_bricked() ? std::make_unique<render::VolumeTracer>(volume.bricked, scene.settings)
                                 : std::make_unique<render::VolumeTracer>(volume.dense, scene.settings);
  });
  VolumeRenderRunResult result;
  render::VolumeFrame frame;
  std::vector<double> frame_ms, frame_cpu_ms;
  for (int i = 0; i < scene.warmup_frames + scene.timed_frames; ++i) {
    const auto t = std::chrono::steady_clock::now();
    const double cpu0 = process_cpu_ms();
    frame = tracer->render(scene.camera);
    const double cpu = process_cpu_ms() - cpu0;
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    if (i >= scene.warmup_frames) frame_ms.push_back(ms), frame_cpu_ms.push_back(cpu);
  }
  result.median_frame_ms = median(frame_ms);
  result.stats = frame.stats;

  write_image(dir / "image.png", render::tf_output_image(frame, scene.tf_output));
  ImageF rgba(frame.radiance.width(), frame.radiance.height(), 4);
  for (int y = 0; y < rgba.height(); ++y)
    for (int x = 0; x < rgba.width(); ++x) {
      for (int c = 0; c < 3; ++c) rgba.at(x, y, c) = frame.radiance.at(x, y, c);
      rgba.at(x, y, 3) = 1.0f - frame.transmittance.at(x, y);
    }
  write_image(dir / "image.exr", rgba, PixelFormat::kFloat);
  std::uint32_t max_count = 0;
  if (o.sample_counts) {
    ImageF counts(frame.radiance.width(), frame.radiance.height(), 1);
    for (std::size_t i = 0; i < frame.sample_counts.size(); ++i) {
      max_count = std::max(max_count, frame.sample_counts[i]);
      counts.values()[i] = float(std::min<std::uint32_t>(frame.sample_counts[i], 65535)) / 65535.0f;
    }
    write_image(dir / "samples.png", counts, PixelFormat::kUint16);
  }

  json j = tf_run_head(o.scene_file, scene, "clv", render::describe_clv(scene, volume), volume.normalisation);
  const render::Box3 d = volume.domain();
  const auto dims = volume.is_bricked() ? volume.bricked.dims() : volume.dense.dims();
  j["volume"] = {
      {"dims", {dims[0], dims[1], dims[2]}},
      {"layout", volume.is_bricked() ? "blocked" : "linear"},
      {"block_side", volume.is_bricked() ? volume.bricked.side() : 0},
      {"sample_type", render::sample_type_name(volume.is_bricked() ? volume.bricked.type() : volume.dense.type())},
      {"domain", {{"lo", {d.lo.x(), d.lo.y(), d.lo.z()}}, {"hi", {d.hi.x(), d.hi.y(), d.hi.z()}}}}};
  if (scene.volume.generate) j["volume"]["generator"] = generator_record(*scene.volume.generate);
  if (!scene.volume.file.empty()) j["volume"]["file"] = scene.volume.file.string();
  if (volume.clv) j["volume"]["clv_header"] = clv_header_json(*volume.clv);
  j["camera"] = camera_json(scene.camera);
  const auto& st = frame.stats;
  j["stats"] = {{"rays", st.rays},
                {"samples", st.samples},
                {"samples_skipped_empty", st.skipped},
                {"rays_terminated_early", st.terminated},
                {"blocks_visible", st.blocks_visible},
                {"block_tasks", st.block_tasks},
                {"queue_empty_fraction", st.block_tasks ? double(st.queue_empty) / double(st.block_tasks) : 0.0},
                {"order_violations", st.order_violations},
                {"render_busy_ms", st.render_busy_ms}};
  if (o.sample_counts) j["stats"]["max_samples_per_pixel"] = max_count;
  j["timing_ms"] = {{"frames", frame_ms},
                    {"median_frame", result.median_frame_ms},
                    {"frames_cpu", frame_cpu_ms},
                    {"median_frame_cpu", median(frame_cpu_ms)},
                    {"warmup_frames", scene.warmup_frames},
                    {"load", load_ms},
                    {"index_build", tracer->index_build_ms()}};
  j["image"] = {{"png", "image.png"},
                {"exr", "image.exr"},
                {"png_output", scene.tf_output == render::TfOutput::kSourceDouble ? "source_double" : "premultiplied"}};
  if (o.sample_counts) j["image"]["sample_counts"] = "samples.png (16-bit: samples per pixel)";
  result.run_json = commit_run(folder, std::move(j), provenance);
  return result;
}

/// Seed 003's slicing renderer (method: slicing): the gradient volume once (through the disk cache
/// under the dataset cache, when the mode lights samples), then warm-up and timed frames.
VolumeRenderRunResult run_slicing_render(const VolumeRenderRunOptions& o, render::VolumeScene& scene) {
  const std::string scene_name = o.scene_file.string();
  auto named = [&](const auto& call) { run_naming_scene(scene_name, call); };
  const auto t_load = std::chrono::steady_clock::now();
  render::SceneVolume loaded = load_linear_scene_volume(scene);
  const render::Volume volume = std::move(loaded.dense);
  const double load_ms = ms_since(t_load);
  render::SlicingScene& sl = *scene.slicing;
  render::SlicingSettings& s = sl.settings;
  // A .vlb/.nrrd load has already mapped its chosen range (scanned, header or window) to [0, 1]; the
  // renderer's own default, the scanned extrema, would stretch a header or window range wider than
  // the data back over the data. So the load's [0, 1] is kept unless the scene gives a value_range.
  // (For a scanned load the two are the same numbers; `normalise: none` keeps the renderer's default.)
  const bool range_from_load =
      loaded.normalisation && loaded.normalisation->source != render::NormSource::kNone && !s.value_range;
  if (range_from_load) s.value_range = std::make_pair(0.0, 1.0);
  named([&] {
    s.mask = render::build_scene_mask(sl, volume.domain());
    render::check_slicing_settings(volume, s);
    const Eigen::Vector3d eye = std::get<render::Pinhole>(scene.camera).camera_from_world.inverse().translation();
    if (volume.domain().contains(eye))
      throw InputError("the camera is inside the volume's box (slicing needs it outside)");
  });
  RunFolder folder(o.out_dir, RunFolderOptions{"--out", "render.json", "volume render", o.overwrite});
  Provenance provenance = start_provenance("volume render", o.command_line);
  const fs::path dir = folder.path();
  std::optional<render::GradientVolume> gradients;
  std::string cache_dir;
  if (render::slicing_needs_gradients(s)) {
    fs::path cache;
    if (sl.cache_gradients) {
      try {
        cache = datasets::default_cache_dir() / "slicing-gradients";
      } catch (const InputError& e) {
        spdlog::warn("slicing: no gradient cache ({})", e.what());
      }
    }
    cache_dir = cache.string();
    gradients = render::cached_gradient_volume(volume, s.gradient, cache);
  }
  if (s.mode == render::SlicingMode::kCombined)
    spdlog::info("slicing: mode combined is the spec's interpretation of the source's words (vsi.combined.rule)");
  const render::SlicingRenderer renderer(volume, s, gradients);
  render::SlicingFrame frame;
  std::vector<double> frame_ms, render_ms, post_ms;
  for (int i = 0; i < scene.warmup_frames + scene.timed_frames; ++i) {
    const auto t = std::chrono::steady_clock::now();
    renderer.render_into(scene.camera, frame);  // the last frame's images reused
    const double ms = ms_since(t);
    if (i >= scene.warmup_frames)
      frame_ms.push_back(ms), render_ms.push_back(frame.stats.render_ms), post_ms.push_back(frame.stats.post_ms);
  }
  VolumeRenderRunResult result;
  result.median_frame_ms = median(frame_ms);
  result.stats.rays = frame.stats.rays;
  result.stats.samples = frame.stats.samples;

  ImageF png(frame.rgb.width(), frame.rgb.height(), 3);
  for (std::size_t i = 0; i < png.size(); ++i)
    png.values()[i] = std::clamp(float(scene.exposure) * frame.rgb.values()[i], 0.0f, 1.0f);
  write_image(dir / "image.png", png);
  ImageF rgba(png.width(), png.height(), 4);
  for (int y = 0; y < rgba.height(); ++y)
    for (int x = 0; x < rgba.width(); ++x) {
      for (int c = 0; c < 3; ++c) rgba.at(x, y, c) = frame.rgb.at(x, y, c);
      rgba.at(x, y, 3) = frame.alpha.at(x, y);
    }
  write_image(dir / "image.exr", rgba, PixelFormat::kFloat);

  json j;
  j["scene_file"] = o.scene_file.string();
  j["method"] = "slicing";
  // The load's normalisation (a .vlb/.nrrd file), then the renderer's choices over it.
  json vsi = vsi_data_json(scene, loaded.normalisation, "vsi.");
  vsi.update(pairs_json(render::describe_vsi(s, volume, scene.camera)));
  const auto [lo, hi] = renderer.value_range();
  vsi["vsi.data.value_range"] = fmt::format("[{:.17g}, {:.17g}]", lo, hi);
  if (range_from_load)
    vsi["vsi.data.norm_source"] = render::norm_source_name(loaded.normalisation->source) + " (at load, to [0, 1])";
  j["vsi"] = vsi;
  j["volume"] = scene_volume_json(scene, volume);
  j["camera"] = camera_json(scene.camera);
  j["stats"] = {{"rays", frame.stats.rays},
                {"samples", frame.stats.samples},
                {"samples_past_mask", frame.stats.classified},
                {"samples_skipped_empty", frame.stats.skipped},
                {"samples_visited", frame.stats.visited},
                {"rays_terminated", frame.stats.terminated},
                {"slices", frame.stats.slices},
                {"slice_spacing", frame.stats.slice_spacing}};
  if (gradients)
    j["gradients"] = {
        {"cache_dir", cache_dir.empty() ? json(nullptr) : json(cache_dir)},
        {"file", cache_dir.empty() ? json(nullptr) : json(render::gradient_cache_name(volume, s.gradient))},
        {"from_cache", gradients->from_cache},
        {"build_ms", gradients->build_ms},
        {"max_magnitude", gradients->max_magnitude}};
  j["timing_ms"] = {{"frames", frame_ms},
                    {"median_frame", result.median_frame_ms},
                    {"median_render", median(render_ms)},
                    {"median_post", median(post_ms)},
                    {"warmup_frames", scene.warmup_frames},
                    {"load", load_ms}};
  j["image"] = {{"png", "image.png"}, {"exr", "image.exr"}, {"exposure", scene.exposure}};
  result.run_json = commit_run(folder, std::move(j), provenance);
  return result;
}

}  // namespace

render::Camera resized_camera(const render::Camera& c, int width, int height) {
  if (width <= 0 && height <= 0) return c;
  auto p = std::get<render::Pinhole>(c);
  const int w = width > 0 ? width : int(std::lround(double(p.width) * height / p.height));
  const int h = height > 0 ? height : int(std::lround(double(p.height) * width / p.width));
  // Keep the field of view: focal lengths and the principal point scale with the image.
  const double sx = double(w) / p.width, sy = double(h) / p.height;
  p.fx *= sx;
  p.fy *= sy;
  p.cx = (p.cx + 0.5) * sx - 0.5;
  p.cy = (p.cy + 0.5) * sy - 0.5;
  p.width = w;
  p.height = h;
  return p;
}

VolumeRenderRunResult run_volume_render(const VolumeRenderRunOptions& o) {
  render::VolumeScene scene = render::read_volume_scene(o.scene_file);
  scene.camera = resized_camera(scene.camera, o.width, o.height);
  if (o.frames) scene.timed_frames = *o.frames;
  if (o.samples) scene.settings.samples = *o.samples;
  if (scene.timed_frames < 1) throw InputError("--frames must be >= 1");
  if (scene.settings.samples < 1) throw InputError("--samples must be >= 1");
  if (scene.slicing) {
    if (o.samples || o.sample_counts) throw InputError("--samples and --sample-counts are for method: ray_casting");
    return run_slicing_render(o, scene);
  }
  if (scene.settings.model == render::OpticalModel::kTransferFunction) return run_tf_render(o, scene);
  if (o.sample_counts) throw InputError("--sample-counts is for model transfer_function");
  const render::SceneVolume loaded = load_linear_scene_volume(scene);
  const render::Volume& volume = loaded.dense;
  ImageF background;
  if (scene.mode == render::VolumeOutputMode::kComposite) {
    background = read_image(scene.background_image);
    if (background.width() != render::camera_width(scene.camera) ||
        background.height() != render::camera_height(scene.camera) || background.channels() < 3)
      throw InputError(fmt::format("{}: the background image must be {}x{} RGB (it is {}x{} with {} channels)",
                                   scene.background_image.string(), render::camera_width(scene.camera),
                                   render::camera_height(scene.camera), background.width(), background.height(),
                                   background.channels()));
    if (background.channels() > 3) {
      ImageF rgb(background.width(), background.height(), 3);
      for (int y = 0; y < rgb.height(); ++y)
        for (int x = 0; x < rgb.width(); ++x)
          for (int c = 0; c < 3; ++c) rgb.at(x, y, c) = background.at(x, y, c);
      background = rgb;
    }
  }
  // Settings the integrator refuses (an eye inside the box, ...) are problems of the scene file.
  const std::string scene_name = o.scene_file.string();
  auto named = [&](const auto& call) { run_naming_scene(scene_name, call); };
  check_eye_outside(scene, volume.domain(), scene_name);
  named([&] { render::check_volume_render_settings(volume, scene.settings); });
  RunFolder folder(o.out_dir, RunFolderOptions{"--out", "render.json", "volume render", o.overwrite});
  Provenance provenance = start_provenance("volume render", o.command_line);
  const fs::path dir = folder.path();

  // Shadow caches once (static light and volume), then warm-up and timed frames.
  VolumeRenderRunResult result;
  std::vector<render::ShadowCache> caches;
  double cache_ms = 0;
  render::VolumeRenderStats cache_stats;
  if (scene.settings.model == render::OpticalModel::kHGAttenuated &&
      scene.settings.shadow == render::ShadowMethod::kCache) {
    const auto t = std::chrono::steady_clock::now();
    const int n = int(render::effective_lights(volume, scene.settings).size());
    for (int l = 0; l < n; ++l) caches.push_back(render::build_shadow_cache(volume, scene.settings, l, &cache_stats));
    cache_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
  }
  render::VolumeFrame frame;
  std::vector<double> frame_ms;
  for (int i = 0; i < scene.warmup_frames + scene.timed_frames; ++i) {
    const auto t = std::chrono::steady_clock::now();
    frame = render::render_volume(volume, scene.camera, scene.settings, caches);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    if (i >= scene.warmup_frames) frame_ms.push_back(ms);
  }
  result.median_frame_ms = median(frame_ms);
  result.stats = frame.stats;

  // Images: the colours over the background (PNG, exposure, clamped) and linear RGBA (EXR).
  const ImageF colour = scene.mode == render::VolumeOutputMode::kComposite
                            ? render::composite_over(frame, background)
                            : render::composite_over(frame, scene.settings.background);
  ImageF png(colour.width(), colour.height(), 3);
  for (std::size_t i = 0; i < colour.size(); ++i)
    png.values()[i] = std::clamp(float(scene.exposure) * colour.values()[i], 0.0f, 1.0f);
  write_image(dir / "image.png", png);
  ImageF rgba(colour.width(), colour.height(), 4);
  for (int y = 0; y < rgba.height(); ++y)
    for (int x = 0; x < rgba.width(); ++x) {
      for (int c = 0; c < 3; ++c) rgba.at(x, y, c) = colour.at(x, y, c);
      rgba.at(x, y, 3) = 1.0f - frame.transmittance.at(x, y);
    }
  write_image(dir / "image.exr", rgba, PixelFormat::kFloat);

  json j = tf_run_head(o.scene_file, scene, "vlr", render::describe_vlr(scene, volume), loaded.normalisation);
  j["volume"] = scene_volume_json(scene, volume);
  j["camera"] = camera_json(scene.camera);
  const auto& st = frame.stats;
  j["stats"] = {{"rays", st.rays},
                {"samples", st.samples},
                {"samples_skipped_empty", st.skipped},
                {"shadow_samples", st.shadow_samples + cache_stats.shadow_samples},
                {"rays_terminated_early", st.terminated},
                {"two_pass_silhouette_mismatch", st.silhouette_mismatch}};
  j["timing_ms"] = {{"frames", frame_ms},
                    {"median_frame", result.median_frame_ms},
                    {"warmup_frames", scene.warmup_frames},
                    {"shadow_cache_build", cache_ms}};
  j["image"] = {{"png", "image.png"},
                {"exr", "image.exr"},
                {"exposure", scene.exposure},
                {"background", scene.mode == render::VolumeOutputMode::kComposite
                                   ? scene.background_image.string()
                                   : fmt::format("[{}, {}, {}]", scene.settings.background.x(),
                                                 scene.settings.background.y(), scene.settings.background.z())}};
  result.run_json = commit_run(folder, std::move(j), provenance);
  return result;
}

}  // namespace meltlab::experiments
