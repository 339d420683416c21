#include <meltlab/core/run_folder.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/compare_run.h>
#include <meltlab/experiments/render_json.h>
#include <meltlab/experiments/run_replay.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/experiments/provenance.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* registration_name(verify::RegistrationMode m) {
  switch (m) {
    case verify::RegistrationMode::kNone:
      return "none";
    case verify::RegistrationMode::kFirstFrame:
      return "first";
    case verify::RegistrationMode::kEveryFrame:
      return "every";
    case verify::RegistrationMode::kGiven:
      return "given";
  }
  return "?";
}

const char* refine_name(verify::RegistrationOptions::Refine r) {
  switch (r) {
    case verify::RegistrationOptions::Refine::kNone:
      return "none";
    case verify::RegistrationOptions::Refine::kIcp:
      return "icp";
    case verify::RegistrationOptions::Refine::kEcc:
      return "ecc";
  }
  return "?";
}

json similarity_json(const verify::Similarity2D& t) {
  return {{"scale", t.scale},
          {"angle_deg", t.angle_rad * 180.0 / 3.14159265358979323846},
          {"tx_px", t.translation.x()},
          {"ty_px", t.translation.y()}};
}

}  // namespace

verify::CompareResult compare_and_write(const verify::ObservationSequence& obs, sim::MeshSequence& meshes,
                                        const verify::CompareOptions& options, const fs::path& out_dir,
                                        int overlay_every,
                                        const std::function<void(const CompareRunProgress&)>& progress,
                                        std::vector<double>* frame_ms) {
  create_output_directories(out_dir, "--out");
  if (overlay_every > 0) create_output_directories(out_dir / "overlays", "--out");
  CompareRunProgress prog;
  prog.total = static_cast<int>(obs.frames.size());
  int compared = 0;
  auto t_frame = std::chrono::steady_clock::now();
  verify::CompareResult result = verify::compare_sequence(
      obs, meshes, options, [&](const verify::FrameResult& r, const verify::FrameImages& images) {
        const auto now = std::chrono::steady_clock::now();
        if (frame_ms) frame_ms->push_back(std::chrono::duration<double, std::milli>(now - t_frame).count());
        t_frame = now;
        ++prog.done;
        if (r.status == "ok") {
          prog.last_P = r.pixels.P;
          if (overlay_every > 0 && compared % overlay_every == 0)
            verify::write_image(out_dir / "overlays" / fmt::format("frame_{:04d}.png", r.frame + 1),
                                verify::overlay_image(images.photo_mask, images.render_mask));
          ++compared;
        } else {
          ++prog.skipped;
        }
        if (progress) progress(prog);
      });
  verify::write_per_frame_csv(out_dir / "per_frame.csv", result.frames);
  verify::write_image(out_dir / "p_curve.png",
                      verify::p_curve_image(
                          result.frames, fmt::format("{}: P per photo",
                                                     obs.object.empty() ? obs.manifest.stem().string() : obs.object)));
  return result;
}

json summarize_frames(const std::vector<verify::FrameResult>& frames) {
  json s;
  int n = 0, accepted = 0, worst = -1;
  double sum = 0, max_p = -1;
  std::optional<double> first, last, first_exact, last_exact;
  for (const auto& f : frames) {
    if (f.status != "ok") continue;
    ++n;
    sum += f.pixels.P;
    if (f.pixels.P <= 0.2) ++accepted;
    if (f.pixels.P > max_p) {
      max_p = f.pixels.P;
      worst = f.frame + 1;
    }
    if (!first) {
      first = f.pixels.P;
      first_exact = f.P_exact;
    }
    last = f.pixels.P;
    last_exact = f.P_exact;
  }
  auto opt = [](const std::optional<double>& v) { return v ? json(*v) : json(nullptr); };
  s["frames_compared"] = n;
  s["frames_skipped"] = static_cast<int>(frames.size()) - n;
  s["P_first"] = opt(first);
  s["P_last"] = opt(last);
  s["P_exact_first"] = opt(first_exact);
  s["P_exact_last"] = opt(last_exact);
  s["P_max"] = n ? json(max_p) : json(nullptr);
  s["P_max_photo"] = n ? json(worst) : json(nullptr);
  s["P_mean"] = n ? json(sum / n) : json(nullptr);
  s["fraction_P_le_0.2"] = n ? json(static_cast<double>(accepted) / n) : json(nullptr);
  json skipped = json::object();
  for (const auto& f : frames)
    if (f.status != "ok") skipped[f.status] = skipped.value(f.status, 0) + 1;
  s["skipped_by_reason"] = skipped;
  return s;
}

CompareRunResult run_compare(const CompareRunOptions& o,
                             const std::function<void(const CompareRunProgress&)>& progress) {
  const auto t_start = std::chrono::steady_clock::now();
  Provenance provenance = start_provenance("compare", o.command_line);
  const auto& m = o.compare.mapping;
  require(!(m.cycles_per_photo && m.seconds_per_cycle),
          "--cycles-per-photo and --seconds-per-cycle exclude each other");
  if (m.cycles_per_photo)
    require(std::isfinite(*m.cycles_per_photo) && *m.cycles_per_photo > 0,
            fmt::format("--cycles-per-photo: must be a finite number > 0 (got {})", *m.cycles_per_photo));
  if (m.seconds_per_cycle)
    require(std::isfinite(*m.seconds_per_cycle) && *m.seconds_per_cycle > 0,
            fmt::format("--seconds-per-cycle: must be a finite number > 0 (got {})", *m.seconds_per_cycle));
  require(std::isfinite(m.first_cycle) && m.first_cycle >= 0,
          fmt::format("--first-cycle: must be a finite number >= 0 (got {})", m.first_cycle));
  require(o.compare.supersample >= 1 && o.compare.supersample <= 16,
          fmt::format("--supersample: must be in [1, 16] (got {})", o.compare.supersample));
  require(o.overlay_every >= 0, "--overlay-every: must be >= 0");
  RunFolder folder(o.out_dir, {"--out", "compare.json", "comparison", o.overwrite});

  const verify::ObservationSequence obs = verify::load_observations(o.observations);
  require(obs.has_photos(), fmt::format("{}: no frames (a mass series alone): compare needs photos; a series is fitted "
                                        "by meltlab fit and predicted by meltlab predict",
                                        obs.manifest.string()));
  RunReplay replay(o.run_dir);
  verify::CompareOptions copt = o.compare;
  copt.last_cycle = replay.cycles_run();
  // Every frame must map to a cycle before anything is written (a missing time is an error).
  for (const auto& f : obs.frames) (void)copt.mapping.cycle_of(f, obs.manifest.string());

  CompareRunResult out;
  std::vector<double> frame_ms;
  out.compare = compare_and_write(obs, replay, copt, folder.path(), o.overlay_every, progress, &frame_ms);
  out.summary = summarize_frames(out.compare.frames);
  json j;
  j["run"] = {{"dir", fs::absolute(o.run_dir).string()},
              {"cycles_run", replay.cycles_run()},
              {"mesh", replay.run_json().value("mesh", json::object())}};
  j["observations"] = {{"manifest", fs::absolute(obs.manifest).string()},
                       {"manifest_hash", file_hash(obs.manifest)},
                       {"object", obs.object},
                       {"frames", obs.frames.size()},
                       {"camera", camera_json(obs.camera)}};
  json mapping;
  if (m.seconds_per_cycle)
    mapping["seconds_per_cycle"] = *m.seconds_per_cycle;
  else
    mapping["cycles_per_photo"] = m.cycles_per_photo.value_or(verify::kDefaultCyclesPerPhoto);
  mapping["first_cycle"] = m.first_cycle;
  j["options"] = {{"mapping", mapping},
                  {"registration", registration_name(copt.registration)},
                  {"refine", refine_name(copt.registration_options.refine)},
                  {"allow_scale", copt.registration_options.allow_scale},
                  {"allow_rotation", copt.registration_options.allow_rotation},
                  {"supersample", copt.supersample},
                  {"exact", copt.exact},
                  {"overlay_every", o.overlay_every}};
  if (out.compare.registration) {
    j["registration"] = similarity_json(*out.compare.registration);
    j["registration"]["P_before"] = out.compare.registration_P_before;
    j["registration"]["P_after"] = out.compare.registration_P_after;
  } else {
    j["registration"] = nullptr;
  }
  j["summary"] = out.summary;
  std::vector<double> sorted = frame_ms;
  std::sort(sorted.begin(), sorted.end());
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  j["timing"] = {{"total_s", total_s},
                 {"frame_ms_median", sorted.empty() ? 0.0 : sorted[sorted.size() / 2]},
                 {"frame_ms_max", sorted.empty() ? 0.0 : sorted.back()}};
  commit_run(folder, std::move(j), provenance);
  return out;
}

}  // namespace meltlab::experiments
