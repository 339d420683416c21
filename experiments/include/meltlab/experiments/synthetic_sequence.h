#pragma once
// `meltlab synth-sequence`: a photo-like observation sequence made by the empirical model
// itself (the "inverse crime" data set: known kg/kl, known outlines). It exercises compare
// and fit end to end where the true answer is known; the physics-based manufactured
// sequences (a different model) come from datasets/.
//
// Output folder:
//   DIR/frames/frame_0001.jpg ...  photos: the silhouette's anti-aliased coverage composited
//                                  as bright ice over a dark textured ground, uneven lighting,
//                                  lens blur, sensor noise, JPEG (or PNG) encoding
//   DIR/manifest.yaml              observation manifest (camera, interval, default segmentation)
//   DIR/volume.csv                 time_s, volume_m3 of the simulated mesh (mesh units = m)
//   DIR/truth/truth.json           parameters, cycle and true area per frame, the misalignment, provenance
//   DIR/truth/masks/frame_0001.png true masks (coverage >= 1/2) in photo coordinates
// The manifest is written last: its presence marks a complete sequence.

#include <meltlab/experiments/simulate_run.h>
#include <meltlab/render/camera.h>
#include <meltlab/verify/compare.h>
#include <meltlab/verify/registration.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct SyntheticSequenceOptions {
  SimulateOptions simulation;  ///< mesh and melt coefficients (out_dir unused)
  int photos = 100;
  double cycles_per_photo = verify::kDefaultCyclesPerPhoto;
  double interval_s = 40.0;              ///< §8.2: a photo every 40 s
  std::optional<render::Camera> camera;  ///< default: orthographic top-down framing the mesh
  int width = 2048, height = 1536;       ///< for the default camera (Coolpix 995)
  double fill = 0.6;                     ///< default camera: fraction of the image the mesh spans
  verify::Similarity2D misalignment;     ///< photo = misalignment(render), e.g. a camera shift
  std::uint64_t seed = 1;
  double noise_sigma = 3.0;    ///< sensor noise, 8-bit levels
  double blur_sigma_px = 1.0;  ///< lens blur
  int jpeg_quality = 92;       ///< 0 writes PNG instead
  std::filesystem::path out_dir;
  bool overwrite = false;
  std::vector<std::string> command_line;  ///< argv, recorded in the provenance of truth/truth.json
};

struct SyntheticProgress {
  int done = 0, total = 0;
};

/// Generates the sequence; throws InputError on bad options (before writing anything).
void make_synthetic_sequence(const SyntheticSequenceOptions& options,
                             const std::function<void(const SyntheticProgress&)>& progress = {});

}  // namespace meltlab::experiments
