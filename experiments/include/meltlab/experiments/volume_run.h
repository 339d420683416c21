#pragma once
// `meltlab volume`: the volume renderers' data and runs.
//   volume generate  the seed-000 volumes (turbulence box/sphere, fireball, constant) into a file
//                    (raw + JSON header with the generator's parameters and a content hash, or .vdb);
//                    seed 001's (shapes, skull) streamed into a .clv file in slices or blocks, in
//                    batches sampled in parallel (render/volume/clv_file.h), with progress on stderr
//   volume render    a scene file (render/volume/volume_scene.h) into a run folder:
//                      DIR/image.png    the pixel colours (I + T·background) × exposure, 8-bit
//                      DIR/image.exr    linear RGB with alpha = 1 - T (composite over anything later)
//                      DIR/render.json  every vlr.* parameter, the volume (dims, hash), the camera,
//                                       counters, timings (warm-up + median of timed frames), provenance
//                    model transfer_function (seed 001): image.png is the 8-bit image of the source
//                    (premultiplied or C·A, truncated), render.json records every clv.* choice, the
//                    load and index times; --sample-counts adds samples.png (16-bit: samples per pixel)
//   volume info      a volume file's dimensions, type, placement, value range and hash (JSON); for a
//                    .clv file its header and layout (the samples are not read)
// Every input is validated before DIR is touched.

#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/volume/clv_file.h>
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
  std::filesystem::path out;        ///< NAME.json (with NAME.raw beside it), NAME.vdb or NAME.clv
  bool overwrite = false;
  // .clv files (seed 001)
  render::ClvOrder order = render::ClvOrder::kLinear;
  int block_side = 16;
  std::int64_t batch = 32768;  ///< clv.gen.batch; 1 = the naive writer (one write() per sample)
  bool progress = true;        ///< progress lines on stderr
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
  bool sample_counts = false;  ///< transfer_function: write samples.png (samples per pixel, 16-bit)
  std::vector<std::string> command_line;
};

struct VolumeRenderRunResult {
  double median_frame_ms = 0;
  render::VolumeRenderStats stats;
  nlohmann::json run_json;
};

/// Validates the scene (InputError naming the file) and renders.
VolumeRenderRunResult run_volume_render(const VolumeRenderRunOptions& options);

/// A pinhole camera at another image size with the same field of view (focal lengths and the
/// principal point scaled; a size <= 0 follows the other at the camera's aspect; both <= 0: unchanged).
render::Camera resized_camera(const render::Camera& camera, int width, int height);

}  // namespace meltlab::experiments
