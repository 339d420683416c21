// meltlab predict: the physically based reference solver's prediction of an experiment,
// against its observed mass series and photos (issue 19).

#include <meltlab/experiments/predict_run.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "cli_util.h"
#include "commands.h"

namespace meltlab::cli {

Run add_predict(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand(
      "predict",
      "Predict a melt with the physically based reference solver and compare it with observations (mass series, "
      "photos): RMSE, time to melt, P per photo");
  auto o = std::make_shared<experiments::PredictOptions>();
  auto mass_g = std::make_shared<double>(0.0);
  o->command_line = command_line;
  auto& ph = o->physics;
  auto* mesh = sub->add_option("--mesh", o->mesh, "The body: a mesh file or dataset name, scaled to its mass of ice");
  auto* shape = sub->add_option("--shape", o->shape,
                                "The body as a shape in mm: box:WxDxH, cylinder:DxH or sphere:D (its mass from its "
                                "size unless --mass-g or a reading at t = 0 gives it)");
  mesh->excludes(shape);
  sub->add_option("--mass-g", *mass_g, "Ice at t = 0 in grams (default: the series' reading at t = 0)");
  sub->add_option("--observations", o->observations,
                  "Manifest of what was observed: a mass_series and/or photos (optional)");
  sub->add_option("--out", o->out_dir, "Output folder (predict.json, prediction.csv, mass_curve.*, comparison/)")
      ->required();
  sub->add_option("--air-C", ph.air_temperature_C, "Air temperature")->default_val(30.0);
  sub->add_option("--ground-C", ph.ground_temperature_C, "Ground temperature")->default_val(30.0);
  sub->add_option("--ice-C", ph.initial_temperature_C, "Initial ice temperature (<= 0)")->default_val(-10.0);
  sub->add_option("--lamp-W-m2", ph.lamp_irradiance_W_m2, "Lamp irradiance from above (0 = no lamp)")->default_val(0.0);
  sub->add_option("--ground-contact-W-m2K", ph.ground_conductance_W_m2K,
                  "Contact conductance between ice and ground (an assumed order of magnitude; 0 = insulated)")
      ->default_val(30.0);
  sub->add_option("--voxel-mm", o->voxel_mm, "Solver grid spacing (mm)")->default_val(2.5);
  sub->add_option("--every-s", o->every_s,
                  "Spacing of the prediction after the observations (0: the observations' own, or 60 s)")
      ->default_val(0.0);
  sub->add_option("--max-time-s", o->max_time_s, "Stop predicting here if the ice has not melted")
      ->default_val(86400.0);
  sub->add_option("--melted-fraction", o->melted_fraction, "'Melted' at or below this fraction of the initial mass")
      ->default_val(0.02);
  std::map<std::string, verify::RegistrationMode> reg{{"none", verify::RegistrationMode::kNone},
                                                      {"first", verify::RegistrationMode::kFirstFrame},
                                                      {"every", verify::RegistrationMode::kEveryFrame}};
  sub->add_option("--registration", o->registration,
                  "Photos: align the predicted silhouette on the first usable photo (first), per photo (every), or "
                  "not (none)")
      ->transform(CLI::CheckedTransformer(reg, CLI::ignore_case))
      ->default_str("first");
  sub->add_option("--overlay-every", o->overlay_every, "Photos: overlay of every K-th compared photo (0 = none)")
      ->default_val(0);
  sub->add_flag("--overwrite", o->overwrite, "Allow --out to hold a previous prediction");
  return [=]() {
    if (sub->count("--mass-g") > 0) o->mass_g = *mass_g;
    ProgressLine line;
    const auto j = experiments::run_predict(*o, [&](const experiments::PredictProgress& p) {
      // The bar: the fraction melted so far.
      const double melted = p.initial_g > 0 ? 1.0 - p.mass_g / p.initial_g : 0.0;
      line.update(std::lround(1000 * std::clamp(melted, 0.0, 1.0)), 1000,
                  fmt::format("‰ melted  t = {:.0f} s  ice {:.1f} g", p.time_s, p.mass_g));
    });
    line.finish();
    auto num = [](const nlohmann::json& v, const char* f) {
      return v.is_null() ? std::string("-") : fmt::format(fmt::runtime(f), v.get<double>());
    };
    std::string what = fmt::format("melted (to {:.3g} g) at {} s", j["prediction"]["melted_level_g"].get<double>(),
                                   num(j["prediction"]["time_to_melt_s"], "{:.0f}"));
    if (!j["series_comparison"].is_null()) {
      const auto& c = j["series_comparison"];
      const auto& observed = c["time_to_melt_s"]["observed"];
      what += fmt::format("; against the series: RMSE {:.3g} g, max error {:.3g} g, {}", c["rmse_g"].get<double>(),
                          c["max_abs_error_g"].get<double>(),
                          observed.is_null() ? std::string("the readings end before it melted")
                                             : fmt::format("melted at {:.0f} s observed", observed.get<double>()));
    }
    if (!j["photos"].is_null())
      what += fmt::format("; photos: P mean {}, max {}", num(j["photos"]["summary"]["P_mean"], "{:.4f}"),
                          num(j["photos"]["summary"]["P_max"], "{:.4f}"));
    std::fprintf(stderr, "meltlab: predict: %s; wrote %s\n", what.c_str(), o->out_dir.string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
