// meltlab fit: the model's coefficients from observations (Ceres).

#include <meltlab/experiments/fit_run.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/fit_parameters.h>

#include <fmt/format.h>

#include <cstdio>
#include <sstream>

#include "cli_util.h"
#include "commands.h"
#include "melt_options.h"

namespace meltlab::cli {

namespace {

double parse_number(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(v)) throw InputError(fmt::format("{}: '{}' is not a number", option, text));
  return v;
}

/// "a=1,b=2" -> {a: 1, b: 2}
std::map<std::string, double> parse_assignments(const std::vector<std::string>& items, const std::string& option) {
  std::map<std::string, double> out;
  for (const std::string& list : items) {
    std::stringstream in(list);
    std::string item;
    while (std::getline(in, item, ',')) {
      const auto eq = item.find('=');
      if (eq == std::string::npos || eq == 0)
        throw InputError(fmt::format("{}: expected name=value, got '{}'", option, item));
      out[item.substr(0, eq)] = parse_number(item.substr(eq + 1), option);
    }
  }
  return out;
}

}  // namespace

Run add_fit(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand(
      "fit", "Fit kg, kl parameters, time scale and registration to an observation sequence (Ceres)");
  auto o = std::make_shared<experiments::FitRunOptions>();
  auto fit = std::make_shared<std::string>();
  auto fix = std::make_shared<std::vector<std::string>>();
  auto initial = std::make_shared<std::vector<std::string>>();
  auto bounds = std::make_shared<std::vector<std::string>>();
  auto no_scan = std::make_shared<bool>(false);
  o->command_line = command_line;
  auto& s = o->simulation;
  sub->add_option("--mesh", s.mesh, "Mesh file or dataset name (the object at the first photo)")->required();
  sub->add_option("--observations", o->observations, "Observation manifest (.yaml/.yml/.json)")->required();
  sub->add_option("--out", o->out_dir, "Output folder (fit.json, comparison/)")->required();
  sub->add_option("--fit", *fit,
                  "Parameters to fit, comma separated (default kg,reg with photos, kg for a mass series): " +
                      verify::fit_parameter_names_help());
  sub->add_option("--fix", *fix, "Fixed values: name=value[,name=value...]");
  sub->add_option("--initial", *initial, "Starting values: name=value[,...]");
  sub->add_option("--bound", *bounds, "Bounds: name=lower:upper (repeatable)");
  // kg is where the fit starts (0.5: mid-range); kN is fitted as "kn" (--fit), not an option.
  MeltOptionSet melt;
  melt.kg = 0.5;
  melt.kg_help = "Starting kg";
  melt.kn = false;
  melt.kl_help = "YAML file with the local coefficient field (its numbers can be fitted)";
  const auto store_melt_options = add_melt_options(*sub, s, melt);
  sub->add_option("--cycles-per-photo", o->cycles_per_photo, "Cycles between photos (start value when fitted)")
      ->default_val(verify::kDefaultCyclesPerPhoto);
  auto seconds_per_cycle = std::make_shared<double>(0.0);
  auto mass_g = std::make_shared<double>(0.0);
  sub->add_option("--seconds-per-cycle", *seconds_per_cycle,
                  "A mass series alone: seconds of the experiment per simulation cycle (start value when fitted; "
                  "without it a fitted time scale starts from the series)");
  sub->add_option("--mass-g", *mass_g,
                  "A mass series alone: the ice at t = 0 in grams (default: the reading at t = 0); the mesh is "
                  "scaled to it");
  sub->add_option("--density", o->density_kg_m3, "A mass series alone: density of ice (kg/m³) for volumes")
      ->default_val(verify::kIceDensity);
  sub->add_option("--first-cycle", o->first_cycle, "Cycle shown by the first photo")->default_val(0);
  sub->add_option("--holdout", o->holdout, "Fraction of the last photos kept out of the fit and predicted")
      ->default_val(0.0);
  sub->add_option("--volume-weight", o->volume_weight,
                  "Also fit the manifest's mass/volume series with this weight (relative volume error x weight ~ px)")
      ->default_val(0.0);
  sub->add_option("--samples", o->fit_options.photo_samples, "Contour points per photo")->default_val(48);
  sub->add_option("--supersample", o->fit_options.supersample, "k x k samples per pixel of the rendered coverage")
      ->default_val(4);
  sub->add_option("--max-iterations", o->fit_options.max_iterations, "Ceres iterations")->default_val(40);
  sub->add_flag("--no-scan", *no_scan, "Skip the coarse scan of kg");
  sub->add_option("--overlay-every", o->overlay_every, "Overlay of every K-th photo of the fitted run (0 = none)")
      ->default_val(10);
  sub->add_flag("--overwrite", o->overwrite, "Allow --out to hold a previous fit");

  return [=]() {
    store_melt_options();
    o->fit.clear();  // empty: the default of the observations (fit_run.h)
    std::stringstream in(*fit);
    std::string item;
    while (std::getline(in, item, ','))
      if (!item.empty()) o->fit.push_back(item);
    if (sub->count("--fit") > 0 && o->fit.empty()) throw InputError("--fit: names no parameter");
    o->cycles_per_photo_given = sub->count("--cycles-per-photo") > 0;
    if (sub->count("--seconds-per-cycle") > 0) o->seconds_per_cycle = *seconds_per_cycle;
    if (sub->count("--mass-g") > 0) o->mass_g = *mass_g;
    o->fix = parse_assignments(*fix, "--fix");
    o->initial = parse_assignments(*initial, "--initial");
    for (const std::string& b : *bounds) {
      const auto eq = b.find('='), colon = b.find(':', eq == std::string::npos ? 0 : eq);
      if (eq == std::string::npos || colon == std::string::npos)
        throw InputError(fmt::format("--bound: expected name=lower:upper, got '{}'", b));
      o->bounds[b.substr(0, eq)] = {parse_number(b.substr(eq + 1, colon - eq - 1), "--bound"),
                                    parse_number(b.substr(colon + 1), "--bound")};
    }
    if (!*no_scan) o->fit_options.kg_scan = {0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 2.0};
    const bool tty = ProgressLine().active();
    const auto j = experiments::run_fit(*o, [&](const std::string& line) {
      if (tty || line.rfind("iteration", 0) != 0) std::fprintf(stderr, "meltlab: fit: %s\n", line.c_str());
    });
    std::string values;
    for (const auto& [name, e] : j["estimates"].items()) {
      if (e["fixed"].get<bool>()) continue;
      values += fmt::format(" {}={:.6g}", name, e["value"].get<double>());
      if (!e["standard_error"].is_null()) values += fmt::format("±{:.2g}", e["standard_error"].get<double>());
    }
    std::string quality;
    if (j.contains("series_comparison"))
      quality = fmt::format("RMSE {:.3g} g", j["series_comparison"]["rmse_g"].get<double>());
    else
      quality = fmt::format("P mean {:.4f}",
                            j["comparison"]["P_mean"].is_null() ? 0.0 : j["comparison"]["P_mean"].get<double>());
    std::fprintf(stderr, "meltlab: fit %s after %d iterations, %d simulations, %.1f s:%s; %s; wrote %s\n",
                 j["converged"].get<bool>() ? "converged" : "stopped", j["iterations"].get<int>(),
                 j["simulations"].get<int>(), j["time_s"].get<double>(), values.c_str(), quality.c_str(),
                 o->out_dir.string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
