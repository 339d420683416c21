#pragma once
// The scene file of `meltlab volume render` (YAML, read through core/config.h: every error is
// FILE:LINE, unknown keys are refused). Every open choice of the seed-000 spec (vlr.*) is a key
// with the spec's default; experiments/configs/volume/*.yaml are examples, one per model:
//
//   model: hg_attenuated          # absorption | emission | emission_absorption | hg | hg_attenuated
//   volume:
//     generate: {kind: turbulence_box, size: 64, octaves: 4, gain: 2, lacunarity: 2,
//                base_frequency: 4, clip: per_octave, seed: 0, falloff: linear, quantization: float32}
//     # or file: cloud.vdb | volume.json     (meltlab's raw + header, or OpenVDB)
//     box: {centre: [0, 0, 0], size: [300, 300, 300]}   # the seed's Box300 (default for generated)
//     address: clamp              # vlr.tex.address: clamp | wrap
//   camera: {type: pinhole, width: 512, height: 512, fov_deg: 45, eye: [400, -550, 300], target: [0, 0, 0], up: [0, 0,
//   1]} sampling: {n: 100, ds_rule: diag_over_n, step: 0, first_offset: zero, seed: 1, last_partial: drop} quadrature:
//   inclusive         # vlr.quad: inclusive (extinction_inclusive) | exclusive | exponential optics: {kappa: 0.01,
//   gamma: 1, albedo: 0.9, hg_c: 0.5, emission: [1, 0.6, 0.2],
//            emission_field: constant, emission_rim: [0.8, 0.1, 0], emission_scale_by_ds: true,
//            kappa_in_source: false, kappa_in_brdf: false, ambient: 0}
//   lights:                       # default: one point light at the box centre + 2 x its sides, L = 1
//     - {type: point, position: [600, 600, 600], intensity: 1, falloff: none}
//     - {type: directional, to_light: [0, 0, 1], intensity: [1, 0.9, 0.8]}
//   shadow: {method: march, step: 0, start_offset: 0.5, cache_build: sweep, cache_scale: 1}
//   acceleration: {ert_transmittance: 0, skip_empty: true}
//   rays: {method: analytic, camera_inside: reject}
//   output: {mode: standalone, background: [0, 0, 0], background_image: earth.png, exposure: 1}
//   timing: {warmup: 3, frames: 20}   # vlr.timing.protocol: frames rendered, the median reported

#include <meltlab/render/camera.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/volume/generate.h>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace meltlab {
class ConfigSection;
}

namespace meltlab::render {

/// Where a scene's volume comes from.
struct VolumeSource {
  std::optional<VolumeGenerateOptions> generate;  ///< generated (the seed's data) ...
  std::filesystem::path file;                     ///< ... or read (meltlab's .json header or .vdb)
  std::optional<Box3> box;                        ///< place the volume in this box (default: as stored)
};

/// vlr.output.mode.
enum class VolumeOutputMode {
  kStandalone,  ///< over the background colour
  kComposite,   ///< over an existing image (background_image), attenuated by the volume's T
};

struct VolumeScene {
  VolumeSource volume;
  Camera camera;
  VolumeRenderSettings settings;
  VolumeOutputMode mode = VolumeOutputMode::kStandalone;
  std::filesystem::path background_image;  ///< composite mode: the image behind the volume
  double exposure = 1.0;                   ///< PNG: colours times this, clamped to [0, 1]
  int warmup_frames = 0, timed_frames = 1;
};

/// Reads a scene file; relative paths in it are taken from the scene's folder.
VolumeScene read_volume_scene(const std::filesystem::path& file);
/// The same from a section (the caller's finish() refuses unknown keys).
VolumeScene parse_volume_scene(const ConfigSection& section, const std::filesystem::path& base_dir);

/// The scene's volume: generated or read, placed in the scene's box (generated volumes default to
/// the seed's 300-unit box centred at the origin).
Volume load_scene_volume(const VolumeScene& scene);

/// Every vlr.* parameter of a render with its resolved value, as name/value text pairs in the
/// spec's order (written to the run record).
std::vector<std::pair<std::string, std::string>> describe_vlr(const VolumeScene& scene, const Volume& volume);

}  // namespace meltlab::render
