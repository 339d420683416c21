#pragma once
// `meltlab render`: melts a mesh and renders it with the ice material on the wet ground
// (monograph chapters 6-7), writing
//   DIR/frames/frame_<cycle>.png|.exr   every K cycles (and the first and last)
//   DIR/frames.csv                      per frame: cycle, triangles, BVH update, timings, mask
//   DIR/render.json                     options, resolved scene, skipped terms, timings, provenance
// or, with liquid_figure, the mask alone after the cycles of Fig. 7.6:
//   DIR/liquid/mask_<cycle>.png         8-bit gray, white = deposit_value, seen from above
//   DIR/liquid/mask_sums.csv            cycle, triangles, mask sum, wet texels, max
// Every input is validated before DIR is touched.

#include <meltlab/experiments/simulate_run.h>
#include <meltlab/sim/liquid_mask.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct RenderRunOptions {
  SimulateOptions melt;              ///< mesh and melt coefficients (out_dir unused)
  std::filesystem::path scene_file;  ///< YAML scene (render_scene.h); empty = defaults
  std::int64_t cycles = 200;
  std::int64_t every = 50;  ///< render a frame every K cycles
  std::filesystem::path out_dir;
  bool overwrite = false;
  bool liquid = true;  ///< false: sublimation (no liquid stage at all)
  int mask_resolution = 256;
  double mask_extent = 3.0;        ///< mask side / the mesh's larger xy extent
  float threshold = 0.5f;          ///< p
  bool threshold_texture = false;  ///< p from a procedural relief texture tp in [p/2, 3p/2]
  double far_fraction = 0.10;
  sim::DepositBlend blend = sim::DepositBlend::kOverwrite;
  char up = 'z';                ///< the mesh's up axis (x, y or z); rotated so it becomes +z
  bool place_on_ground = true;  ///< translate the mesh so its lowest point is z = 0
  int width = 0, height = 0;    ///< override the scene's size (0 = keep)
  bool liquid_figure = false;   ///< Fig. 7.6 mode: masks only
  std::vector<std::int64_t> figure_cycles{100, 400, 700, 1000, 2000, 3000, 6000, 10000};
  std::vector<std::string> command_line;  ///< argv, recorded in the provenance of the run record
};

struct RenderRunResult {
  std::int64_t cycles_run = 0;
  std::int64_t frames = 0;
  std::int64_t melted_at_cycle = -1;
  double median_trace_ms = 0;
  nlohmann::json run_json;
};

/// Validates the options (throws InputError naming the option) and runs.
RenderRunResult run_render(const RenderRunOptions& options);

}  // namespace meltlab::experiments
