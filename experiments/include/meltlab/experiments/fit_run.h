#pragma once
// `meltlab fit`: fits kg, kl parameters, the time scale and the registration of the
// empirical model to an observation sequence (verify/fit.h) and writes
//   DIR/fit.json          estimates, standard errors, correlations, costs, iterations,
//                         simulations, time, the kg scan, frames used/refused, hold-out P,
//                         and (if the manifest's ground truth names them) the true values; provenance
//   DIR/comparison/       per_frame.csv, overlays/, p_curve.png of the fitted run (all
//                         frames, held-out ones included)
// Every input is validated before DIR is touched; fit.json is written last.

#include <meltlab/experiments/simulate_run.h>
#include <meltlab/verify/fit.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct FitRunOptions {
  SimulateOptions simulation;  ///< mesh, kE, kr, kl file, precision (kg = initial value)
  std::filesystem::path observations;
  std::filesystem::path out_dir;
  std::vector<std::string> fit = {"kg", "reg"};  ///< names to fit ("reg" = all four reg.*)
  std::map<std::string, double> fix;             ///< fixed values
  std::map<std::string, double> initial;         ///< starting values
  std::map<std::string, std::pair<double, double>> bounds;
  double cycles_per_photo = verify::kDefaultCyclesPerPhoto;  ///< initial / fixed K
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
                                                 const std::map<std::string, double>& kl_values);

}  // namespace meltlab::experiments
