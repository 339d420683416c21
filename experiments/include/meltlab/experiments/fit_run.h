#pragma once
// `meltlab fit`: fits kg, kl parameters, the time scale and the registration of the
// empirical model to an observation sequence (verify/fit.h) and writes
//   DIR/fit.json          estimates with three errors each (Ceres', per photo clustered,
//                         total) and the segmentation bias, "uncertainty" (what they mean),
//                         "warnings" (what biases the fit), correlations, costs, iterations,
//                         simulations, time, the kg scan, frames used/refused, hold-out P,
//                         and (if the manifest's ground truth names them) the true values; provenance
//   DIR/comparison/       per_frame.csv, overlays/, p_curve.png of the fitted run (all
//                         frames, held-out ones included)
// A weighing experiment (a manifest with a mass_series and no frames, issue 19) fits kg (or
// the time scale seconds_per_cycle, or kl/kn numbers) to the mass curve instead:
//   DIR/fit.json          the same keys where they apply, the series (rows used and left
//                         out, noise), the fitted curve against it (RMSE, max error, times)
//   DIR/mass_curve.csv    time_s, observed_g, fitted_g, used (1/0) per reading
//   DIR/mass_curve.png    readings and the fitted model's curve (to its melt)
// Every input is validated before DIR is touched; fit.json is written last.

#include <meltlab/experiments/simulate_run.h>
#include <meltlab/verify/fit.h>
#include <meltlab/verify/mass_series.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct FitRunOptions {
  SimulateOptions simulation;  ///< mesh, kE, kr, kl file, precision (kg = initial value)
  std::filesystem::path observations;
  std::filesystem::path out_dir;
  /// Names to fit ("reg" = all four reg.*); empty: kg and reg with photos, kg for a series.
  std::vector<std::string> fit = {"kg", "reg"};
  std::map<std::string, double> fix;      ///< fixed values
  std::map<std::string, double> initial;  ///< starting values
  std::map<std::string, std::pair<double, double>> bounds;
  double cycles_per_photo = verify::kDefaultCyclesPerPhoto;  ///< initial / fixed K
  bool cycles_per_photo_given = false;                       ///< --cycles-per-photo was on the command line
  // A mass series alone:
  std::optional<double> seconds_per_cycle;     ///< initial / fixed S (without it a free S starts from the series)
  std::optional<double> mass_g;                ///< the ice at t = 0 (default: the reading at t = 0)
  double density_kg_m3 = verify::kIceDensity;  ///< of ice, turns masses into volumes
  double first_cycle = 0;
  double holdout = 0;        ///< fraction of the last frames kept out of the fit
  double volume_weight = 0;  ///< > 0: fit the manifest's mass/volume series too
  verify::FitOptions fit_options;
  int overlay_every = 10;
  bool overwrite = false;
  std::vector<std::string> command_line;  ///< argv, recorded in the provenance of the run record
};

/// Runs the fit and writes DIR; returns fit.json.
nlohmann::json run_fit(const FitRunOptions& options, const std::function<void(const std::string&)>& log);

/// The parameter list of a fit: every name with its initial value, bounds, scale and fixed
/// flag (exposed for tests). Throws InputError for unknown names or values outside bounds.
std::vector<verify::FitParameter> fit_parameters(const FitRunOptions& options, double kg_initial,
                                                 const std::map<std::string, double>& kl_values,
                                                 bool series_only = false);

}  // namespace meltlab::experiments
