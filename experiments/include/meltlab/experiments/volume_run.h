#pragma once
// `meltlab volume`: the volume renderers' data and runs.
//   volume generate  the seed-000 volumes (turbulence box/sphere, fireball, constant) into a file
//                    (raw + JSON header with the generator's parameters and a content hash, or .vdb)
//   volume render    a scene file (render/volume/volume_scene.h) into a run folder:
//                      DIR/image.png    the pixel colours (I + T·background) × exposure, 8-bit
//                      DIR/image.exr    linear RGB with alpha = 1 - T (composite over anything later)
//                      DIR/render.json  every vlr.* parameter, the volume (dims, hash), the camera,
//                                       counters, timings (warm-up + median of timed frames), provenance
//   volume info      a volume file's dimensions, type, placement, value range and hash (JSON)
// Every input is validated before DIR is touched.

#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/volume/generate.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct VolumeGenerateRunOptions {
  render::VolumeGenerateOptions generate;
  std::optional<render::Box3> box;  ///< the world box (default: the unit box [0, 1]^3)
  std::filesystem::path out;        ///< NAME.json (with NAME.raw beside it) or NAME.vdb
  bool overwrite = false;
};

/// Generates and writes the volume; returns its description (volume_info of the written file).
nlohmann::json run_volume_generate(const VolumeGenerateRunOptions& options);

/// A volume file's description: dims, sample type, placement, domain, value range, content hash.
nlohmann::json volume_info(const std::filesystem::path& file);

struct VolumeRenderRunOptions {
  std::filesystem::path scene_file;
  std::filesystem::path out_dir;
  bool overwrite = false;
  int width = 0, height = 0;   ///< override the camera's image size (0 = keep; the field of view is kept)
  std::optional<int> frames;   ///< override the scene's timed frames
  std::optional<int> samples;  ///< override vlr.sampling.n
  std::vector<std::string> command_line;
};

struct VolumeRenderRunResult {
  double median_frame_ms = 0;
  render::VolumeRenderStats stats;
  nlohmann::json run_json;
};

/// Validates the scene (InputError naming the file) and renders.
VolumeRenderRunResult run_volume_render(const VolumeRenderRunOptions& options);

}  // namespace meltlab::experiments
