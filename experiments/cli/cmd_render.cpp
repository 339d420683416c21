// meltlab render: melt a mesh and render it with the ice material on the wet ground
// (monograph chapters 6-7), or write the liquid mask of Fig. 7.6.

#include <meltlab/experiments/render_run.h>

#include <fmt/format.h>

#include <cstdio>
#include <map>

#include "cli_util.h"
#include "commands.h"
#include "melt_options.h"

namespace meltlab::cli {

Run add_render(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand(
      "render", "Melt a mesh and ray-trace it as ice on a wet ground (Eq. 6.11, 7.17), or --liquid-figure");
  auto o = std::make_shared<experiments::RenderRunOptions>();
  auto no_liquid = std::make_shared<bool>(false);
  auto no_place = std::make_shared<bool>(false);
  auto blend = std::make_shared<std::string>("overwrite");
  o->command_line = command_line;
  sub->add_option("--mesh", o->melt.mesh, "Mesh file (.off .ply .obj .stl) or a dataset name (meltlab dataset list)")
      ->required();
  sub->add_option("--scene", o->scene_file,
                  "YAML scene: camera, texture_filter, lights, ice, ground, environment (lat-long or cube map), "
                  "outputs; every key in experiments/configs/render_ice.yaml (default: built in)");
  sub->add_option("--cycles", o->cycles, "Melt cycles to run")->default_val(200);
  sub->add_option("--every", o->every, "Render a frame every K cycles (and the last)")->default_val(50);
  sub->add_option("--out", o->out_dir, "Output folder (frames/, frames.csv, render.json)")->required();
  sub->add_option("--width", o->width, "Image width for the automatic camera (overrides the scene's)")->default_val(0);
  sub->add_option("--height", o->height, "Image height for the automatic camera (overrides the scene's)")
      ->default_val(0);
  // Render melts in double precision with coefficients relative to L0 and kN = kE / 100.
  MeltOptionSet melt;
  melt.kn = melt.units = melt.kl = melt.precision = false;
  melt.threads = true;
  const auto store_melt_options = add_melt_options(*sub, o->melt, melt);
  sub->add_flag("--no-liquid", *no_liquid, "Sublimation: no liquid stage (the mask is neither evolved nor shaded)");
  sub->add_option("--mask-resolution", o->mask_resolution, "Liquid mask texels per side")->default_val(256);
  sub->add_option("--mask-extent", o->mask_extent, "Mask side / the mesh's larger horizontal extent")->default_val(3.0);
  sub->add_option("--threshold", o->threshold, "Liquid presence threshold p (Eq. 7.7)")->default_val(0.5);
  sub->add_flag("--threshold-texture", o->threshold_texture,
                "p from a relief texture tp in [p/2, 3p/2] (Eq. 7.14-7.17)");
  sub->add_option("--far-fraction", o->far_fraction, "Deposit slab height / object thickness (§7.3.2)")
      ->default_val(0.10);
  sub->add_option("--deposit-blend", *blend, "overwrite (draw into the uncleared mask) or add")
      ->check(CLI::IsMember({"overwrite", "add"}))
      ->default_val("overwrite");
  auto up = std::make_shared<std::string>("z");
  sub->add_option("--up", *up, "The mesh's up axis; rotated (cyclically) to +z before melting")
      ->check(CLI::IsMember({"x", "y", "z"}))
      ->default_val("z");
  sub->add_flag("--keep-position", *no_place, "Do not move the mesh so its lowest point is on the ground z = 0");
  sub->add_flag("--liquid-figure", o->liquid_figure,
                "Write only the liquid mask after the cycles of Fig. 7.6 (+ mask_sums.csv)");
  sub->add_option("--figure-cycles", o->figure_cycles, "Cycles at which --liquid-figure writes the mask")
      ->delimiter(',')
      ->default_str("100,400,700,1000,2000,3000,6000,10000");
  sub->add_flag("--overwrite", o->overwrite, "Allow --out to hold a previous render");
  return [=]() {
    store_melt_options();
    o->liquid = !*no_liquid;
    o->place_on_ground = !*no_place;
    o->up = (*up)[0];
    o->blend = *blend == "add" ? sim::DepositBlend::kAdd : sim::DepositBlend::kOverwrite;
    const auto r = experiments::run_render(*o);
    if (o->liquid_figure)
      std::fprintf(stderr, "meltlab: liquid figure after %lld cycles; wrote %s\n", static_cast<long long>(r.cycles_run),
                   o->out_dir.string().c_str());
    else
      std::fprintf(stderr, "meltlab: %lld frames over %lld cycles; median %.1f ms/frame; wrote %s\n",
                   static_cast<long long>(r.frames), static_cast<long long>(r.cycles_run), r.median_trace_ms,
                   o->out_dir.string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
