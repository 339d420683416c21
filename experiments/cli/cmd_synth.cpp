// meltlab synth-sequence: a photo-like sequence made by the empirical model (known truth).

#include <meltlab/experiments/synthetic_sequence.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "cli_util.h"
#include "commands.h"
#include "melt_options.h"

namespace meltlab::cli {

namespace {

/// "dx,dy,deg,scale" -> similarity (photo = s R p + t).
verify::Similarity2D parse_misalignment(const std::string& text) {
  std::istringstream in(text);
  double v[4] = {0, 0, 0, 1};
  char comma = 0;
  for (int i = 0; i < 4; ++i) {
    if (!(in >> v[i]) || (i < 3 && !(in >> comma && comma == ','))) {
      throw InputError(fmt::format("--misalign: expected dx,dy,deg,scale (pixels, degrees, factor), got '{}'", text));
    }
  }
  std::string rest;
  if (in >> rest) throw InputError(fmt::format("--misalign: trailing text in '{}'", text));
  verify::Similarity2D t;
  t.translation = {v[0], v[1]};
  t.angle_rad = v[2] * 3.14159265358979323846 / 180.0;
  t.scale = v[3];
  return t;
}

}  // namespace

Run add_synth_sequence(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand(
      "synth-sequence",
      "Render a photo-like observation sequence of the empirical melt (inverse-crime data with known truth)");
  auto o = std::make_shared<experiments::SyntheticSequenceOptions>();
  o->command_line = command_line;
  auto misalign = std::make_shared<std::string>();
  auto& s = o->simulation;
  sub->add_option("--mesh", s.mesh, "Mesh file or dataset name (the object at cycle 0)")->required();
  const auto store_melt_options = add_melt_options(*sub, s, MeltOptionSet{});
  sub->add_option("--photos", o->photos, "Number of photos")->default_val(100);
  sub->add_option("--cycles-per-photo", o->cycles_per_photo, "Simulation cycles between photos")
      ->default_val(verify::kDefaultCyclesPerPhoto);
  sub->add_option("--interval-s", o->interval_s, "Seconds between photos")->default_val(40.0);
  sub->add_option("--width", o->width, "Image width of the default top-down camera (px)")->default_val(2048);
  sub->add_option("--height", o->height, "Image height of the default top-down camera (px)")->default_val(1536);
  sub->add_option("--fill", o->fill, "Fraction of the image the object's footprint spans")->default_val(0.6);
  sub->add_option("--misalign", *misalign, "Camera misalignment dx,dy,deg,scale applied to the photos (px, degrees)");
  sub->add_option("--seed", o->seed, "Seed of the textures and the sensor noise")->default_val(1);
  sub->add_option("--noise", o->noise_sigma, "Sensor noise sigma (8-bit levels)")->default_val(3.0);
  sub->add_option("--blur", o->blur_sigma_px, "Lens blur sigma (px)")->default_val(1.0);
  sub->add_option("--jpeg-quality", o->jpeg_quality, "JPEG quality; 0 writes PNG")->default_val(92);
  sub->add_option("--out", o->out_dir, "Output folder")->required();
  sub->add_flag("--overwrite", o->overwrite, "Allow --out to hold a previous sequence");

  return [=]() {
    store_melt_options();
    if (!misalign->empty()) o->misalignment = parse_misalignment(*misalign);
    ProgressLine line;
    experiments::make_synthetic_sequence(
        *o, [&](const experiments::SyntheticProgress& p) { line.update(p.done, p.total, "photos"); });
    line.finish();
    std::fprintf(stderr, "meltlab: wrote %d photos, manifest.yaml and truth/ to %s\n", o->photos,
                 o->out_dir.string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
