#pragma once
// `meltlab fog`: seed 002's spotlights in homogeneous fog (render/fog/).
//
// `fog render`: one of the procedural scenes of the spec §4 (S1 sphere, S2 street, S3 lamp as a
// spotlight or a point light) through the two-pass fog renderer (visibility, then the per-pixel
// model with the tables) into a run folder: image.png, image.exr, render.json (every fsa.* choice,
// the tables' domains and warps, the lookups beyond a table's domain, timings).
//
// `fog bench`: the accuracy and cost studies of the spec §3 and §6, as CSV for the report
// (report/experiments/fog_seed002.py):
//   tables.csv  E1: lookup error of F, H, G_1 (the spec's G_0) and G_20 at random points for
//               N = 16 … 1024 (G up to 512 in quick mode), both axis warps of the airlight table.
//   e2.csv      E2: the airlight against R-air on every pixel of S1-S3 and on the S4 rays, per N,
//               table function and warp: median, p99, max, mean relative error (floor 1e-4 of the
//               image maximum), and the accurate-F model against R-air (the derivation's floor).
//   e3.csv      E3: L_p against R-surf-model on lit surface pixels of S1, per N (G tables).
//   model.csv   the model error: L_p (accurate G) against R-surf-true over k_t·l and the cone angle.
//   cost.csv    shading time against lit pixels (S1 at 5 resolutions), lights (S2, 1-16) and
//               triangle count (S1 as a mesh, 1k-1M triangles, Embree visibility timed apart).
//   speed.csv   airlight time and E2 of the analytic model (N = 64) and of uniform-step ray
//               marching at a range of steps, on S1 and S2: the speed ratio at equal error.
//   bench.json  the options, table descriptions, load averages, provenance.

#include <filesystem>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct FogRenderOptions {
  std::string scene = "sphere";  ///< sphere, street, lamp_spot, lamp_point
  double kt = 0.04;
  int width = 640, height = 480, lights = 4;
  int table_n = 64;
  std::string table_function = "H", u_warp = "cbrt", v_warp = "sqrt_hi", v_interp = "value";
  std::string view_attenuation = "apply", specular_args = "mirror", cone_solver = "robust";
  std::string terms = "all";  ///< all, no_airlight (Fig. 5.2 b), direct (no fog terms at all)
  double exposure = 1.0;
  std::filesystem::path out_dir;
  bool overwrite = false;
  std::vector<std::string> command_line;
};

struct FogRenderResult {
  double visibility_ms = 0, shading_ms = 0;
  long long lit_pixels = 0, lookups = 0, clamped = 0;
};

FogRenderResult run_fog_render(const FogRenderOptions& options);

struct FogBenchOptions {
  std::vector<std::string> studies{"tables", "e2", "e3", "model", "cost", "speed"};
  bool quick = true;
  int warmup = 1, repeats = 5;
  std::filesystem::path out_dir;
  bool overwrite = false;
  std::vector<std::string> command_line;
};

void run_fog_bench(const FogBenchOptions& options);

}  // namespace meltlab::experiments
