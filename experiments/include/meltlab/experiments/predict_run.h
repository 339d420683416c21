#pragma once
// `meltlab predict` (issue 19): what the physically based reference solver (sim/physics, the
// enthalpy method) predicts for the conditions of an experiment, and how well that matches
// what was observed. Nothing is fitted: the physics has no free melt coefficient.
//
// The body: --mesh (a file or dataset name) or --shape (box, cylinder, sphere in mm), scaled
// to its mass of ice at t = 0 (--mass-g; else the series' reading at t = 0; else, for a
// shape, its own size) and put on the ground as `meltlab manufacture` does
// (experiments/physics_body.h). The conditions: air, ground and ice temperatures, lamp,
// ground contact, grid spacing (sim/physics/enthalpy.h names every constant's source).
//
// With --observations (a manifest): its mass series is compared reading by reading (RMSE,
// largest error, mean error, half-mass time and time to melt, predicted against observed);
// its photos, if any, are compared with the predicted ice's silhouette through the
// manifest's camera (P per photo, verify::compare_sequence with the solver as the mesh
// sequence: no photo is rendered). The solver is advanced once, forward, through every
// reading's and photo's time, then on until the ice has melted (or --max-time-s), so the
// prediction at a reading is the solver's state at exactly that time; a series made by
// `meltlab manufacture` with the same conditions is reproduced exactly.
//
// Writes DIR/predict.json (conditions, body, prediction, comparisons, timings, provenance),
// DIR/prediction.csv (time_s, mass_g, volume_m3 of the predicted curve), with a series
// DIR/mass_curve.csv (per reading: time_s, observed_g, predicted_g, used) and
// DIR/mass_curve.png, with photos DIR/comparison/ (per_frame.csv, p_curve.png, overlays
// only with --overlay-every). Every input is checked before DIR is touched.

#include <meltlab/sim/physics/enthalpy.h>
#include <meltlab/verify/compare.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct PredictOptions {
  std::string mesh;                     ///< dataset name or file (one of mesh, shape)
  std::string shape;                    ///< "box:WxDxH", "cylinder:DxH", "sphere:D" (mm)
  std::optional<double> mass_g;         ///< the ice at t = 0
  double voxel_mm = 2.5;                ///< solver grid spacing
  sim::physics::IceMeltParams physics;  ///< air 30 °C, ice -10 °C, ground 30 °C, ...
  std::filesystem::path observations;   ///< optional manifest (a mass series and/or photos)
  double every_s = 0;                   ///< spacing of the predicted curve after the observations (0: theirs, or 60 s)
  double max_time_s = 86400;            ///< the prediction stops here if the ice has not melted
  double melted_fraction = 0.02;        ///< "melted": at or below this fraction of the initial mass
  verify::RegistrationMode registration = verify::RegistrationMode::kFirstFrame;
  int overlay_every = 0;
  std::filesystem::path out_dir;
  bool overwrite = false;
  std::vector<std::string> command_line;
};

struct PredictProgress {
  double time_s = 0, mass_g = 0, initial_g = 0;
};

/// Runs the prediction and writes DIR; returns predict.json.
nlohmann::json run_predict(const PredictOptions& options, const std::function<void(const PredictProgress&)>& progress);

}  // namespace meltlab::experiments
