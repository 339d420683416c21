// meltlab manufacture: photo-like sequences of a physically based melt (issue 4).

#include <meltlab/experiments/manufacture.h>

#include <fmt/format.h>

#include <cstdio>

#include "cli_util.h"
#include "commands.h"

namespace meltlab::cli {

Run add_manufacture(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand(
      "manufacture",
      "Melt an ice body with the physically based reference solver and photograph it (observations with truth)");
  auto o = std::make_shared<experiments::ManufactureOptions>();
  o->command_line = command_line;
  auto& ph = o->physics;
  sub->add_option("--mesh", o->mesh, "Mold or mesh (dataset name or file); scaled to --mass-g of ice")->required();
  sub->add_option("--out", o->out_dir, "Output folder")->required();
  sub->add_option("--mass-g", o->mass_g, "Ice mass")->default_val(250.0);
  sub->add_option("--photos", o->photos, "Number of photos")->default_val(200);
  sub->add_option("--interval-s", o->interval_s, "Seconds between photos")->default_val(40.0);
  sub->add_option("--voxel-mm", o->voxel_mm, "Solver grid spacing (mm)")->default_val(2.5);
  sub->add_option("--air-C", ph.air_temperature_C, "Air temperature")->default_val(30.0);
  sub->add_option("--ice-C", ph.initial_temperature_C, "Initial ice temperature")->default_val(-10.0);
  sub->add_option("--ground-C", ph.ground_temperature_C, "Ground temperature")->default_val(30.0);
  sub->add_option("--lamp-W-m2", ph.lamp_irradiance_W_m2, "Lamp irradiance (0 = no lamp)")->default_val(0.0);
  sub->add_option("--width", o->width, "Image width (px)")->default_val(1024);
  sub->add_option("--height", o->height, "Image height (px)")->default_val(768);
  sub->add_option("--camera-height-m", o->camera_height_m, "Camera height above the ground (m)")->default_val(0.8);
  sub->add_option("--fill", o->fill, "Fraction of the image the object spans")->default_val(0.6);
  sub->add_option("--noise", o->photo.noise_sigma, "Sensor noise sigma (8-bit levels)")->default_val(2.0);
  sub->add_option("--blur", o->photo.lens_blur_sigma_px, "Lens blur sigma (px)")->default_val(0.7);
  sub->add_option("--jpeg-quality", o->jpeg_quality, "JPEG quality")->default_val(90);
  sub->add_option("--mesh-every", o->mesh_every, "Write the ice surface every K-th photo (0 = never)")->default_val(10);
  sub->add_option("--seed", o->seed, "Seed of ground texture and noise")->default_val(1);
  sub->add_flag("--overwrite", o->overwrite, "Allow --out to hold a previous sequence");
  return [=]() {
    ProgressLine line;
    experiments::manufacture_sequence(*o, [&](const experiments::ManufactureProgress& p) {
      line.update(p.done, p.total, fmt::format("photos  t = {:.0f} s  ice {:.1f} g", p.time_s, p.mass_g));
    });
    line.finish();
    std::fprintf(stderr, "meltlab: wrote %d photos, manifest.yaml, mass.csv and truth/ to %s\n", o->photos,
                 o->out_dir.string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
