#include <meltlab/verify/fit_parameters.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meltlab::verify {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool starts_with(std::string_view s, std::string_view prefix) { return s.substr(0, prefix.size()) == prefix; }

}  // namespace

FitParameterRole fit_parameter_role(std::string_view name) {
  if (starts_with(name, kKlParameterPrefix)) return FitParameterRole::kKlField;
  if (starts_with(name, "reg.")) return FitParameterRole::kRegistration;
  if (name == "cycles_per_photo" || name == "seconds_per_cycle") return FitParameterRole::kTimeScale;
  return FitParameterRole::kMeltSettings;
}

bool is_model_parameter(std::string_view name) {
  const FitParameterRole r = fit_parameter_role(name);
  return r == FitParameterRole::kMeltSettings || r == FitParameterRole::kKlField;
}

std::vector<FitParameterSpec> fit_parameter_table(const FitParameterContext& c) {
  using R = FitParameterRole;
  // kn, the weight of the normal term M_N (Eq. 3.6): flat faces creep at kg·kN per cycle while
  // convex features move at up to kg·kE, so kN/kE shapes how thin parts melt against broad
  // ones. Bounded by kE (the monograph's kN << kE). A change of kE/200 moves a flat side by
  // ≈ 0.5 L0 over 100 photos of 7 cycles, many pixels.
  // Name order: the fit's parameter vector (and fit.json's "free" list) follows it.
  if (c.series_only) {
    // seconds_per_cycle: a change of 5 % moves the end of the melt by 5 % of its time, far
    // above the resolution of a scale; the fit may move its start (fit.h, the time scale).
    return {
        {"kg", R::kMeltSettings, c.kg_initial, 0.01, 1.0, 0.05, "global melt rate"},
        {"kn", R::kMeltSettings, c.kn_initial, 0.0, std::max(c.kE, c.kn_initial), std::max(c.kE / 200.0, 1e-9),
         "weight of M_N, --kn units"},
        {"seconds_per_cycle", R::kTimeScale, c.seconds_per_cycle, 1e-6, 1e9, 0.05 * c.seconds_per_cycle,
         "seconds of the experiment per simulation cycle (the time scale of a mass series)"},
    };
  }
  return {
      {"cycles_per_photo", R::kTimeScale, c.cycles_per_photo, 0.25, 1000.0, 0.5,
       "simulation cycles between photos (the time scale)"},
      {"kg", R::kMeltSettings, c.kg_initial, 0.01, 1.0, 0.05, "global melt rate"},
      {"kn", R::kMeltSettings, c.kn_initial, 0.0, std::max(c.kE, c.kn_initial), std::max(c.kE / 200.0, 1e-9),
       "weight of M_N, --kn units"},
      {"reg.angle_deg", R::kRegistration, 0, -45, 45, 0.2, "rotation about the pivot (deg)"},
      {"reg.scale", R::kRegistration, 1, 0.7, 1.4, 0.004, "scale about the pivot"},
      {"reg.tx_px", R::kRegistration, 0, -500, 500, 1.0, "shift in x (photo px)"},
      {"reg.ty_px", R::kRegistration, 0, -500, 500, 1.0, "shift in y (photo px)"},
  };
}

FitParameterSpec kl_fit_parameter(const std::string& name, double value) {
  return {name,
          FitParameterRole::kKlField,
          value,
          value >= 0 ? 0.0 : -kInf,
          kInf,
          std::max(std::abs(value) * 0.05, 1e-4),
          "a number in the --kl YAML"};
}

std::vector<std::string> registration_parameter_names() {
  return {"reg.tx_px", "reg.ty_px", "reg.angle_deg", "reg.scale"};
}

std::string fit_parameter_names(bool series_only) {
  if (series_only) return "kg, kn, seconds_per_cycle, kl.<path in the --kl file>";
  std::string out = "kg, kn, cycles_per_photo, reg";
  for (const std::string& r : registration_parameter_names()) out += ", " + r;
  return out + ", kl.<path in the --kl file>";
}

std::string fit_parameter_names_help() {
  const std::vector<FitParameterSpec> table = fit_parameter_table({});
  auto help_of = [&](const std::string& name) {
    for (const FitParameterSpec& s : table)
      if (s.name == name) return fmt::format("{} ({})", name, s.help);
    return name;
  };
  std::string regs;
  for (const std::string& r : registration_parameter_names()) regs += (regs.empty() ? "" : ",") + r;
  FitParameterContext series;
  series.series_only = true;
  std::string seconds;
  for (const FitParameterSpec& s : fit_parameter_table(series))
    if (s.name == "seconds_per_cycle") seconds = fmt::format("{} ({}; no photos)", s.name, s.help);
  return fmt::format("{}, {}, {}, reg (= {}), kl.<path in the --kl YAML, e.g. kl.of.0.strength>; {}", help_of("kg"),
                     help_of("kn"), help_of("cycles_per_photo"), regs, seconds);
}

}  // namespace meltlab::verify
