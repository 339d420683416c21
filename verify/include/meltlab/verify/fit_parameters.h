#pragma once
// The fit's parameters, registered once (issue 14 §2): name, how the fit applies it, its
// default, bounds and characteristic scale. verify/fit.cpp asks the table how to apply a
// name; `meltlab fit` (experiments/fit_run.cpp, cli/cmd_fit.cpp) builds its parameter list,
// parses --fit and writes its help text from it.

#include <meltlab/verify/compare.h>  // kDefaultCyclesPerPhoto

#include <string>
#include <string_view>
#include <vector>

namespace meltlab::verify {

/// How a parameter enters the fit.
enum class FitParameterRole {
  kMeltSettings,  ///< a sim::MeltParams coefficient (kg, kn): passed to FitModel::start
  kKlField,       ///< a number in the kl field's YAML ("kl.<path>"): passed to FitModel::start
  kTimeScale,     ///< cycles_per_photo (photos) or seconds_per_cycle (a mass series): time -> cycles
  kRegistration,  ///< reg.*: the render -> photo similarity about the pivot
};

/// What the table needs from the run to size the parameters whose range depends on it.
struct FitParameterContext {
  double kg_initial = 0.5;                           ///< the run's starting kg
  double kE = 1.0;                                   ///< the run's edge coefficient (bounds kn)
  double kn_initial = 0.01;                          ///< the run's kN (default kE / 100)
  double cycles_per_photo = kDefaultCyclesPerPhoto;  ///< the run's starting K
  /// A weighing experiment (a mass series, no photos): the time scale is seconds_per_cycle
  /// and there is no registration (fit_parameter_table then lists kg, kn, seconds_per_cycle).
  bool series_only = false;
  double seconds_per_cycle = 1.0;  ///< the run's starting S (series only)
};

/// One registered parameter with its default (starting value), bounds and scale: the size of
/// a change that moves the contours by about a pixel or more (the central-difference step of
/// the fit is a fraction of it).
struct FitParameterSpec {
  std::string name;
  FitParameterRole role = FitParameterRole::kMeltSettings;
  double initial = 0, lower = 0, upper = 0, scale = 1;
  std::string help;  ///< one phrase for the CLI
};

/// The prefix of kl field parameters ("kl.of.0.strength").
inline constexpr std::string_view kKlParameterPrefix = "kl.";
/// The name that stands for all four registration parameters in --fit.
inline constexpr std::string_view kRegistrationGroup = "reg";

/// How `name` is applied: kl.* -> kKlField, reg.* -> kRegistration, cycles_per_photo ->
/// kTimeScale, anything else -> kMeltSettings (the model decides whether it knows it).
FitParameterRole fit_parameter_role(std::string_view name);
/// True for the names FitModel::start receives (melt settings and kl field numbers).
bool is_model_parameter(std::string_view name);

/// Every fixed-name parameter (kg, kn, cycles_per_photo, reg.*; for a series alone kg, kn,
/// seconds_per_cycle), in name order, with the values of `context`.
std::vector<FitParameterSpec> fit_parameter_table(const FitParameterContext& context);
/// A kl field number as a parameter: non-negative if it starts so, scale 5 % of its value.
FitParameterSpec kl_fit_parameter(const std::string& name, double value);
/// The registration parameters "reg" expands to.
std::vector<std::string> registration_parameter_names();
/// "kg, kn, cycles_per_photo, reg, reg.tx_px, …, kl.<path in the --kl file>": the names an
/// unknown-name error lists (with `series_only`: "kg, kn, seconds_per_cycle, kl.<…>").
std::string fit_parameter_names(bool series_only = false);
/// The same with a phrase each, for --fit's help text.
std::string fit_parameter_names_help();

}  // namespace meltlab::verify
