#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/experiments/compare_run.h>
#include <meltlab/experiments/physics_body.h>
#include <meltlab/experiments/predict_run.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/experiments/render_json.h>
#include <meltlab/experiments/series_output.h>
#include <meltlab/experiments/simulate_run.h>
#include <meltlab/sim/mesh_io.h>
#include <meltlab/sim/physics/isosurface.h>
#include <meltlab/verify/mass_series.h>
#include <meltlab/verify/observations.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// The solver stepped forward through a list of times ("checkpoints"), the mass recorded at
/// each. As a mesh sequence, "cycle" k is photo k: the ice surface (marching tetrahedra) at
/// the photo's time; the photos' times are among the checkpoints.
class PhysicsRun final : public sim::MeshSequence {
 public:
  PhysicsRun(sim::physics::EnthalpySolver& solver, std::vector<double> checkpoints, std::vector<double> photo_times,
             const std::function<void(const PredictProgress&)>& progress)
      : solver_(solver),
        checkpoints_(std::move(checkpoints)),
        photo_times_(std::move(photo_times)),
        progress_(progress) {}

  /// Advances through every checkpoint up to `t` and to `t` itself, as manufacture does:
  /// one advance(t - now) per time.
  void advance_to(double t) {
    while (next_ < checkpoints_.size() && checkpoints_[next_] <= t) step_to(checkpoints_[next_++]);
    step_to(t);
  }

  const sim::TriMesh<double>& mesh_at(std::int64_t k) override {
    if (k < 0 || static_cast<std::size_t>(k) >= photo_times_.size())
      throw InvariantError(fmt::format("PhysicsRun: no photo {}", k));
    advance_to(photo_times_[static_cast<std::size_t>(k)]);
    const auto t0 = std::chrono::steady_clock::now();
    mesh_ = sim::TriMesh<double>::from_indexed(sim::physics::isosurface(solver_.ice_fraction()));
    surfaces_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return mesh_;
  }

  verify::MassCurve curve;
  std::vector<double> volume_m3;
  double solver_s = 0, surfaces_s = 0;  ///< time in the solver and in the isosurfaces

 private:
  void step_to(double t) {
    const auto t0 = std::chrono::steady_clock::now();
    if (t > solver_.time_s()) solver_.advance(t - solver_.time_s());
    solver_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!curve.time_s.empty() && !(t > curve.time_s.back())) return;  // recorded already
    curve.time_s.push_back(t);
    curve.mass_g.push_back(solver_.ice_mass_kg() * 1000.0);
    volume_m3.push_back(solver_.ice_volume_m3());
    if (progress_) progress_({t, curve.mass_g.back(), curve.mass_g.front()});
  }

  sim::physics::EnthalpySolver& solver_;
  std::vector<double> checkpoints_, photo_times_;
  std::size_t next_ = 0;
  const std::function<void(const PredictProgress&)>& progress_;
  sim::TriMesh<double> mesh_;
};

json optional_json(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }

}  // namespace

json run_predict(const PredictOptions& o, const std::function<void(const PredictProgress&)>& progress) {
  const auto t_start = std::chrono::steady_clock::now();
  require(o.mesh.empty() != o.shape.empty(), "--mesh or --shape: give exactly one (the body of ice)");
  if (o.mass_g) require(std::isfinite(*o.mass_g) && *o.mass_g > 0, "--mass-g: must be > 0");
  require(std::isfinite(o.voxel_mm) && o.voxel_mm >= 0.2 && o.voxel_mm <= 20, "--voxel-mm: must be in [0.2, 20]");
  require(std::isfinite(o.every_s) && o.every_s >= 0, "--every-s: must be >= 0");
  require(std::isfinite(o.max_time_s) && o.max_time_s > 0 && o.max_time_s <= 1e7, "--max-time-s: must be in (0, 1e7]");
  require(o.melted_fraction > 0 && o.melted_fraction < 1, "--melted-fraction: must be in (0, 1)");
  require(o.overlay_every >= 0, "--overlay-every: must be >= 0");
  const auto& ph = o.physics;
  require(std::isfinite(ph.air_temperature_C) && ph.air_temperature_C > -50 && ph.air_temperature_C < 100,
          "--air-C: must be in (-50, 100)");
  require(std::isfinite(ph.ground_temperature_C) && ph.ground_temperature_C > -50 && ph.ground_temperature_C < 100,
          "--ground-C: must be in (-50, 100)");
  require(std::isfinite(ph.initial_temperature_C) && ph.initial_temperature_C <= 0 && ph.initial_temperature_C > -100,
          "--ice-C: must be in (-100, 0]");
  require(std::isfinite(ph.lamp_irradiance_W_m2) && ph.lamp_irradiance_W_m2 >= 0, "--lamp-W-m2: must be >= 0");
  require(!std::isnan(ph.ground_conductance_W_m2K) && ph.ground_conductance_W_m2K >= 0,
          "--ground-contact-W-m2K: must be >= 0");
  RunFolder folder(o.out_dir, {"--out", "predict.json", "prediction", o.overwrite});
  Provenance provenance = start_provenance("predict", o.command_line);

  // ---- observations (optional) ----
  std::optional<verify::ObservationSequence> obs;
  std::optional<verify::MeltSeries> series;
  if (!o.observations.empty()) {
    obs = verify::load_observations(o.observations);
    if (obs->mass_series) series = load_melt_series(*obs, ph.density_kg_m3);
  }
  std::vector<double> photo_times;
  if (obs && obs->has_photos()) {
    for (const verify::Frame& f : obs->frames) {
      require(f.time_s.has_value(), fmt::format("{}: frame {} ({}) has no time; predict needs time_s or interval_s",
                                                obs->manifest.string(), f.index + 1, f.image.filename().string()));
      require(*f.time_s >= 0, fmt::format("{}: frame {} is at t = {} s, before the start", obs->manifest.string(),
                                          f.index + 1, *f.time_s));
      photo_times.push_back(*f.time_s);
    }
  }

  // ---- the body ----
  std::string source, mass_from;
  sim::IndexedMesh mesh;
  if (!o.shape.empty()) {
    mesh = shape_mesh(o.shape);
    source = o.shape;
  } else {
    const fs::path path = resolve_mesh_argument(o.mesh);
    mesh = sim::load_mesh(path).mesh;
    source = path.string();
  }
  double mass0_g = 0;
  bool scaled_to_reading = false;  // the body is scaled to the series' reading at t = 0
  if (o.mass_g) {
    mass0_g = *o.mass_g;
    mass_from = "--mass-g";
  } else if (series && series->time_s.front() == 0) {
    mass0_g = initial_mass_g(*series, std::nullopt, mass_from);
    scaled_to_reading = true;
  } else if (!o.shape.empty()) {
    double v = 0;
    for (const auto& t : mesh.F) v += mesh.V[t[0]].dot(mesh.V[t[1]].cross(mesh.V[t[2]])) / 6.0;
    mass0_g = v * ph.density_kg_m3 * 1000.0;
    mass_from = fmt::format("the size of {} ({:.6g} cm³ of ice)", o.shape, v * 1e6);
  } else if (series) {
    mass0_g = initial_mass_g(*series, std::nullopt, mass_from);  // refuses: no reading at t = 0
  } else {
    throw InputError(
        fmt::format("--mass-g: the mass of {} at t = 0 is needed (no series reading at t = 0, no --shape)", o.mesh));
  }
  const PhysicsBody body = make_physics_body(std::move(mesh), mass0_g, o.voxel_mm, ph, source);
  sim::physics::EnthalpySolver solver(body.fraction, ph);
  const double voxel_mass_g = solver.ice_mass_kg() * 1000.0;

  // ---- the times the solver passes through ----
  std::vector<double> checkpoints = photo_times;
  if (series) {
    checkpoints.insert(checkpoints.end(), series->time_s.begin(), series->time_s.end());
    checkpoints.insert(checkpoints.end(), series->left_out_readings.time_s.begin(),
                       series->left_out_readings.time_s.end());
  }
  checkpoints.push_back(0.0);
  std::sort(checkpoints.begin(), checkpoints.end());
  checkpoints.erase(std::unique(checkpoints.begin(), checkpoints.end()), checkpoints.end());
  require(checkpoints.back() <= o.max_time_s,
          fmt::format("--max-time-s: {} s ends before the last observation at {} s", o.max_time_s, checkpoints.back()));
  double every = o.every_s;
  if (every <= 0) {
    std::vector<double> gaps;
    for (std::size_t i = 1; i < checkpoints.size(); ++i) gaps.push_back(checkpoints[i] - checkpoints[i - 1]);
    std::sort(gaps.begin(), gaps.end());
    every = gaps.empty() ? 60.0 : gaps[gaps.size() / 2];
  }
  PhysicsRun run(solver, checkpoints, photo_times, progress);
  double photos_s = 0;

  // ---- photos: P per photo against the predicted ice's silhouette ----
  json photos_json = nullptr;
  if (!photo_times.empty()) {
    verify::CompareOptions copt;
    copt.mapping.cycles_per_photo = 1.0;  // "cycle" k = photo k (PhysicsRun)
    copt.registration = o.registration;
    const auto t0 = std::chrono::steady_clock::now();
    const verify::CompareResult cmp =
        compare_and_write(*obs, run, copt, folder.path() / "comparison", o.overlay_every, {});
    photos_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() - run.solver_s - run.surfaces_s;
    photos_json = {{"frames", obs->frames.size()},
                   {"camera", camera_json(obs->camera)},
                   {"registration", o.registration == verify::RegistrationMode::kNone         ? "none"
                                    : o.registration == verify::RegistrationMode::kEveryFrame ? "every"
                                                                                              : "first"},
                   {"summary", summarize_frames(cmp.frames)},
                   {"outputs", {{"per_frame", "comparison/per_frame.csv"}, {"p_curve", "comparison/p_curve.png"}}}};
  }
  // ---- the rest of the observations, then on until the ice has melted ----
  run.advance_to(checkpoints.back());
  const double level = o.melted_fraction * mass0_g;
  for (double t = checkpoints.back() + every; t <= o.max_time_s + 1e-9 * every; t += every) {
    run.advance_to(t);
    if (run.curve.mass_g.back() <= 0.5 * level) break;  // the melted level is bracketed
  }

  std::ostringstream csv;
  csv << "time_s,mass_g,volume_m3\n";
  for (std::size_t i = 0; i < run.curve.time_s.size(); ++i)
    csv << fmt::format("{},{:.9g},{:.9g}\n", run.curve.time_s[i], run.curve.mass_g[i], run.volume_m3[i]);
  write_text_atomically(folder.path() / "prediction.csv", csv.str());

  json j;
  j["body"] = {{"source", source},
               {"scale", body.scale},
               {"shift_m", {body.shift.x(), body.shift.y(), body.shift.z()}},
               {"initial_mass_g", mass0_g},
               {"initial_mass_from", mass_from},
               {"voxelised_mass_g", voxel_mass_g},
               {"voxel_mm", o.voxel_mm},
               {"grid", {body.fraction.nx, body.fraction.ny, body.fraction.nz}}};
  j["conditions"] = {{"air_C", ph.air_temperature_C},
                     {"ground_C", ph.ground_temperature_C},
                     {"ice_C", ph.initial_temperature_C},
                     {"lamp_W_m2", ph.lamp_irradiance_W_m2},
                     {"ground_conductance_W_m2K", ph.ground_conductance_W_m2K},
                     {"h_up_W_m2K", ph.h_up_W_m2K},
                     {"h_vertical_W_m2K", ph.h_vertical_W_m2K},
                     {"h_down_W_m2K", ph.h_down_W_m2K},
                     {"density_kg_m3", ph.density_kg_m3},
                     {"time_step_s", solver.time_step_s()}};
  j["prediction"] = {{"points", run.curve.time_s.size()},
                     {"end_time_s", run.curve.time_s.back()},
                     {"end_mass_g", run.curve.mass_g.back()},
                     {"every_s", every},
                     {"half_mass_time_s", optional_json(verify::time_to_fall_to(run.curve, 0.5 * mass0_g))},
                     {"time_to_melt_s", optional_json(verify::time_to_fall_to(run.curve, level))},
                     {"melted_level_g", level},
                     {"curve", "prediction.csv"}};
  j["observations"] = obs ? json{{"manifest", fs::absolute(obs->manifest).string()},
                                 {"manifest_hash", file_hash(obs->manifest)},
                                 {"object", obs->object}}
                          : json(nullptr);
  j["series"] = series ? series_json(*series) : json(nullptr);
  j["series_comparison"] = nullptr;
  if (series) {
    // The reading the body was scaled to has no error by construction: not scored.
    const std::size_t first = scaled_to_reading ? 1 : 0;
    const verify::SeriesComparison cmp =
        verify::compare_series(verify::mass_curve(*series), run.curve, mass0_g, o.melted_fraction, first);
    j["series_comparison"] = series_comparison_json(cmp, "predicted");
    write_mass_curve_csv(folder.path() / "mass_curve.csv", *series, run.curve, "predicted");
    verify::write_image(
        folder.path() / "mass_curve.png",
        verify::mass_curve_image(
            verify::mass_curve(*series), {{"physics (enthalpy solver)", run.curve}},
            fmt::format("{}: predicted and observed mass", obs->object.empty() ? "series" : obs->object), level,
            series->left_out_readings));
  }
  j["photos"] = photos_json;
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  // photos: the comparison of the silhouettes with the photos (segmentation, silhouettes, P),
  // without the solver and the isosurfaces it waited for.
  j["timing"] = {
      {"solver_s", run.solver_s}, {"surfaces_s", run.surfaces_s}, {"photos_s", photos_s}, {"total_s", total_s}};
  provenance.timings_s.emplace_back("solver", run.solver_s);
  return commit_run(folder, std::move(j), provenance);
}

}  // namespace meltlab::experiments
