// `meltlab volume generate | render | info` (see volume_run.h).

#include <meltlab/experiments/volume_run.h>

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/experiments/render_json.h>
#include <meltlab/render/volume/volume_io.h>
#include <meltlab/render/volume/volume_scene.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>

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

render::Camera resized(const render::Camera& c, int width, int height) {
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

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

json volume_info(const fs::path& file) {
  const render::Volume v = render::read_volume(file);
  json j = volume_json(v);
  j["file"] = file.string();
  return j;
}

json run_volume_generate(const VolumeGenerateRunOptions& o) {
  const std::string ext = o.out.extension().string();
  if (ext != ".json" && ext != ".vdb")
    throw InputError(
        fmt::format("--out {}: name the header NAME.json (raw samples in NAME.raw) or NAME.vdb", o.out.string()));
  fs::path raw = o.out;
  raw.replace_extension(".raw");
  for (const fs::path& f : {o.out, raw}) {
    std::error_code ec;
    if (fs::is_directory(f, ec)) throw InputError(fmt::format("--out {}: is a folder", f.string()));
    if (fs::exists(f, ec) && !o.overwrite && (f == o.out || ext == ".json"))
      throw InputError(fmt::format("--out {}: exists (use --overwrite to replace it)", f.string()));
  }
  if (o.out.has_parent_path()) create_output_directories(o.out.parent_path(), "--out");
  render::Volume v = render::generate_volume(o.generate);
  if (o.box) v.fit_to_box(*o.box);
  render::write_volume(o.out, v, generator_record(o.generate));
  json j = volume_json(v);
  j["file"] = o.out.string();
  j["generator"] = generator_record(o.generate);
  return j;
}

VolumeRenderRunResult run_volume_render(const VolumeRenderRunOptions& o) {
  render::VolumeScene scene = render::read_volume_scene(o.scene_file);
  scene.camera = resized(scene.camera, o.width, o.height);
  if (o.frames) scene.timed_frames = *o.frames;
  if (o.samples) scene.settings.samples = *o.samples;
  if (scene.timed_frames < 1) throw InputError("--frames must be >= 1");
  if (scene.settings.samples < 1) throw InputError("--samples must be >= 1");
  const render::Volume volume = render::load_scene_volume(scene);
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
  auto named = [&](const auto& call) {
    try {
      call();
    } catch (const InputError& e) {
      const std::string what = e.what();
      if (what.rfind(scene_name, 0) == 0) throw;
      throw InputError(fmt::format("{}: {}", scene_name, what));
    }
  };
  if (const auto* pin = std::get_if<render::Pinhole>(&scene.camera)) {
    const Eigen::Vector3d eye = pin->camera_from_world.inverse().translation();
    if (volume.domain().contains(eye) && scene.settings.camera_inside == render::CameraInside::kReject)
      throw InputError(
          fmt::format("{}: the camera is inside the volume's box (vlr.camera.inside: reject); move it "
                      "out or set rays: {{camera_inside: start_at_eye}}",
                      scene_name));
  }
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

  json j;
  j["scene_file"] = o.scene_file.string();
  j["model"] = render::optical_model_name(scene.settings.model);
  json vlr = json::object();
  for (const auto& [k, v] : render::describe_vlr(scene, volume)) vlr[k] = v;
  j["vlr"] = vlr;
  j["volume"] = volume_json(volume);
  if (scene.volume.generate) j["volume"]["generator"] = generator_record(*scene.volume.generate);
  if (!scene.volume.file.empty()) j["volume"]["file"] = scene.volume.file.string();
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
