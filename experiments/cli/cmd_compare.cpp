// meltlab compare: a simulate run against a photo sequence (monograph chapter 8).

#include <meltlab/experiments/compare_run.h>

#include <fmt/format.h>

#include <cstdio>
#include <map>

#include "cli_util.h"
#include "commands.h"

namespace meltlab::cli {

Run add_compare(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand(
      "compare", "Compare a simulate run with an observed photo sequence: P (Eq. 8.1) per photo, overlays, P curve");
  auto o = std::make_shared<experiments::CompareRunOptions>();
  auto cycles_per_photo = std::make_shared<double>(verify::kDefaultCyclesPerPhoto);
  auto seconds_per_cycle = std::make_shared<double>(0.0);
  auto no_exact = std::make_shared<bool>(false);
  auto fixed_scale = std::make_shared<bool>(false);
  auto fixed_rotation = std::make_shared<bool>(false);
  o->command_line = command_line;

  sub->add_option("--sim", o->run_dir, "Folder of a `meltlab simulate` run (its run.json is replayed)")->required();
  sub->add_option("--observations", o->observations, "Observation manifest (.yaml/.yml/.json)")->required();
  sub->add_option("--out", o->out_dir, "Output folder (per_frame.csv, overlays/, p_curve.png, compare.json)")
      ->required();
  auto* cpp = sub->add_option(
      "--cycles-per-photo", *cycles_per_photo,
      fmt::format("Simulation cycles between consecutive photos (default {}: ~700 cycles per 100 photos, §8.2)",
                  verify::kDefaultCyclesPerPhoto));
  auto* spc = sub->add_option("--seconds-per-cycle", *seconds_per_cycle,
                              "Real seconds per simulation cycle (uses the photos' time stamps)");
  cpp->excludes(spc);
  sub->add_option("--first-cycle", o->compare.mapping.first_cycle, "Cycle shown by the first photo")->default_val(0);
  std::map<std::string, verify::RegistrationMode> reg{{"none", verify::RegistrationMode::kNone},
                                                      {"first", verify::RegistrationMode::kFirstFrame},
                                                      {"every", verify::RegistrationMode::kEveryFrame}};
  sub->add_option(
         "--registration", o->compare.registration,
         "Align render to photo: on the first usable frame and keep it (first), per frame (every), or not (none)")
      ->transform(CLI::CheckedTransformer(reg, CLI::ignore_case))
      ->default_str("first");
  std::map<std::string, verify::RegistrationOptions::Refine> refine{
      {"none", verify::RegistrationOptions::Refine::kNone},
      {"icp", verify::RegistrationOptions::Refine::kIcp},
      {"ecc", verify::RegistrationOptions::Refine::kEcc}};
  sub->add_option("--refine", o->compare.registration_options.refine,
                  "Refinement after the moment-based start: contour ICP, OpenCV ECC, or none")
      ->transform(CLI::CheckedTransformer(refine, CLI::ignore_case))
      ->default_str("icp");
  sub->add_flag("--fixed-scale", *fixed_scale, "Registration may not scale (the camera scale is trusted)");
  sub->add_flag("--fixed-rotation", *fixed_rotation, "Registration may not rotate");
  sub->add_option("--supersample", o->compare.supersample,
                  "k x k samples per pixel of the render used for the sub-pixel contour (exact P, distances)")
      ->default_val(4);
  sub->add_flag("--no-exact", *no_exact, "Skip the exact polygon P (CGAL)");
  sub->add_option("--overlay-every", o->overlay_every, "Write the overlay of every K-th compared frame (0 = none)")
      ->default_val(1);
  sub->add_flag("--overwrite", o->overwrite, "Allow --out to hold a previous comparison");

  return [=]() {
    if (spc->count() > 0) {
      o->compare.mapping.seconds_per_cycle = *seconds_per_cycle;
    } else {
      o->compare.mapping.cycles_per_photo = *cycles_per_photo;
    }
    o->compare.exact = !*no_exact;
    o->compare.registration_options.allow_scale = !*fixed_scale;
    o->compare.registration_options.allow_rotation = !*fixed_rotation;
    ProgressLine line;
    const auto result = experiments::run_compare(*o, [&](const experiments::CompareRunProgress& p) {
      line.update(p.done, p.total, fmt::format("photos  P = {:.4f}  skipped {}", p.last_P, p.skipped));
    });
    line.finish();
    const auto& s = result.summary;
    auto num = [](const nlohmann::json& v) {
      return v.is_null() ? std::string("-") : fmt::format("{:.4f}", v.get<double>());
    };
    std::fprintf(stderr, "meltlab: compared %d photos (%d skipped): P first %s, last %s, max %s, mean %s; wrote %s\n",
                 s["frames_compared"].get<int>(), s["frames_skipped"].get<int>(), num(s["P_first"]).c_str(),
                 num(s["P_last"]).c_str(), num(s["P_max"]).c_str(), num(s["P_mean"]).c_str(),
                 o->out_dir.string().c_str());
    return s["frames_compared"].get<int>() > 0 ? kExitOk : kExitInvalid;
  };
}

}  // namespace meltlab::cli
