// meltlab fog: seed 002's spotlights in fog (render/fog/): render the procedural scenes S1-S3,
// and the accuracy and cost studies.

#include <meltlab/experiments/fog.h>

#include <cstdio>

#include "cli_util.h"
#include "commands.h"

namespace meltlab::cli {

Run add_fog(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand("fog", "Spotlights in fog (seed 002): render scenes S1-S3, accuracy and cost studies");
  sub->require_subcommand(1);

  auto* ren = sub->add_subcommand("render", "Render a procedural fog scene (S1 sphere, S2 street, S3 lamp)");
  auto r = std::make_shared<experiments::FogRenderOptions>();
  r->command_line = command_line;
  ren->add_option("--scene", r->scene, "sphere, street, lamp_spot or lamp_point")
      ->check(CLI::IsMember({"sphere", "street", "lamp_spot", "lamp_point"}))
      ->default_val("sphere");
  ren->add_option("--kt", r->kt, "Extinction coefficient k_t, 1/m (fsa.medium.kt)")->default_val(0.04);
  ren->add_option("--width", r->width, "Image width")->default_val(640);
  ren->add_option("--height", r->height, "Image height")->default_val(480);
  ren->add_option("--lights", r->lights, "Street lamps (scene street)")->default_val(4);
  ren->add_option("--table-n", r->table_n, "Table nodes per axis (fsa.table.N)")->default_val(64);
  ren->add_option("--table-function", r->table_function, "F (the source) or H (the tail, the harness's default)")
      ->default_val("H");
  ren->add_option("--u-warp", r->u_warp,
                  "none, sqrt, cbrt, sqrt_hi or smooth: the u axis of the airlight table (fsa.table.axis_warp)")
      ->default_val("cbrt");
  ren->add_option("--v-warp", r->v_warp,
                  "none, sqrt, cbrt, sqrt_hi or smooth: the v axis of the airlight table (fsa.table.v_warp)")
      ->default_val("sqrt_hi");
  ren->add_option("--v-interp", r->v_interp,
                  "index or value: bilinear in the v axis' warped index or in v itself (fsa.table.v_interp)")
      ->default_val("value");
  ren->add_option("--view-attenuation", r->view_attenuation, "apply or source_omit (fsa.surface.view_attenuation)")
      ->default_val("apply");
  ren->add_option("--specular-args", r->specular_args, "mirror or source (fsa.errata.specular_args)")
      ->default_val("mirror");
  ren->add_option("--cone-solver", r->cone_solver, "robust or source (fsa.cone.solver)")->default_val("robust");
  ren->add_option("--terms", r->terms, "all, no_airlight (Fig. 5.2 b) or direct (no fog terms)")->default_val("all");
  ren->add_option("--exposure", r->exposure, "PNG exposure")->default_val(1.0);
  ren->add_option("--out", r->out_dir, "Output folder (image.png, image.exr, render.json)")->required();
  ren->add_flag("--overwrite", r->overwrite, "Allow --out to hold a previous render");

  auto* bench = sub->add_subcommand("bench", "E1/E2/E3, the model error, cost shapes, speed against ray marching");
  auto b = std::make_shared<experiments::FogBenchOptions>();
  b->command_line = command_line;
  auto full = std::make_shared<bool>(false);
  bench->add_option("--study", b->studies, "tables, e2, e3, model, cost, speed (default: all)")->delimiter(',');
  bench->add_flag("--full", *full, "Full sizes (default: quick)");
  bench->add_option("--warmup", b->warmup, "Runs before timing")->default_val(1);
  bench->add_option("--repeats", b->repeats, "Timed runs (the median is reported)")->default_val(5);
  bench->add_option("--out", b->out_dir, "Output folder (CSV files, bench.json)")->required();
  bench->add_flag("--overwrite", b->overwrite, "Allow --out to hold a previous bench");

  return [=]() {
    if (bench->parsed()) {
      b->quick = !*full;
      experiments::run_fog_bench(*b);
      std::fprintf(stderr, "meltlab: fog bench: wrote %s\n", b->out_dir.string().c_str());
      return kExitOk;
    }
    const auto res = experiments::run_fog_render(*r);
    std::fprintf(
        stderr,
        "meltlab: fog render: %lld lit pixels, shading %.1f ms; %lld of %lld lookups beyond a table; wrote %s\n",
        res.lit_pixels, res.shading_ms, res.clamped, res.lookups, r->out_dir.string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
