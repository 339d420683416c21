#pragma once
// The scene file of `meltlab volume render` (YAML, read through core/config.h: every error is
// FILE:LINE, unknown keys are refused). Every open choice of the seed-000 spec (vlr.*) and of the
// seed-001 spec (clv.*) is a key with the spec's default; experiments/configs/volume/*.yaml are
// examples, one per model:
//
//   model: hg_attenuated          # absorption | emission | emission_absorption | hg | hg_attenuated
//                                 # | transfer_function (seed 001)
//   volume:
//     generate: {kind: turbulence_box, size: 64, octaves: 4, gain: 2, lacunarity: 2,
//                base_frequency: 4, clip: per_octave, seed: 0, falloff: linear, quantization: float32}
//     # seed 001: {kind: shapes, size: 256 (or dims: [x, y, z]), shapes: 70, sample: 100,
//     #            object_size: 70, seed: 2} | {kind: skull, dims: [256, 256, 68], seed: 1}
//     # seed 003: {kind: ct_phantom, dims: [256, 256, 113], spacing: [1, 1, 2], noise_hu: 20, seed: 1}
//     # or file: cloud.vdb | volume.json | volume.clv  (meltlab's raw + header, OpenVDB, seed 001's)
//     #        | head.vlb | head.nrrd | head.nhdr      (seed 003's medical formats)
//     normalise: scanned          # .vlb/.nrrd/.nhdr: vsi.data.norm_source: scanned | header | window
//                                 # (VLB lines 6, 7) | none (stored values, e.g. HU)
//     window_units: fraction      # vsi.data.window_units: VLB line 7 as fractions of line 6 | value
//     box: {centre: [0, 0, 0], size: [300, 300, 300]}   # the seed's Box300 (default for seed 000's
//                                                       # generated volumes; seed 001's: voxel units)
//     address: clamp              # vlr.tex.address: clamp | wrap
//     memory: mmap                # .clv files: mmap (read-only, shared) | ram (a copy)
//     samples: stored             # stored (8-bit) | float32 (converted at load, 4x the memory)
//     layout: as_stored           # as_stored | linear | blocked (converted in memory)
//     block_side: 16              # layout: blocked
//   camera: {type: pinhole, width: 512, height: 512, fov_deg: 45, eye: [400, -550, 300],
//            target: [0, 0, 0], up: [0, 0, 1]}
//   sampling: {n: 100, ds_rule: diag_over_n, step: 0, first_offset: zero, seed: 1, last_partial: drop}
//             # ds_rule: diag_over_n | fit_segment | fixed_step (seed 001: step 0.2)
//   quadrature: inclusive         # vlr.quad: inclusive (extinction_inclusive) | exclusive | exponential
//   optics: {kappa: 0.01, gamma: 1, albedo: 0.9, hg_c: 0.5, emission: [1, 0.6, 0.2],
//            emission_field: constant, emission_rim: [0.8, 0.1, 0], emission_scale_by_ds: true,
//            kappa_in_source: false, kappa_in_brdf: false, ambient: 0}
//   transfer_function:            # model transfer_function (clv.tf.*, clv.shade.*, clv.gradient.*)
//     table: shapes               # shapes | skull | a list of ranges:
//                                 #   [{range: "(85, 95]", rgb: [255, 30, 60], alpha: 0.02}, ...]
//     reference_step: 0           # s0 in scene units; 0 = one voxel
//     opacity_exponent: s_over_s0 # s_over_s0 (correct) | s0_over_s (the thesis's printed erratum)
//     shading: {enabled: true, gradient: central, threshold: 2.0, light_dir: [-4, -3, -2],
//               ka: 0.16, q: 128, ks: 120}   # gradient: central | one_sided (the repo)
//     output: premultiplied       # clv.output.final_multiply: premultiplied | source_double (C·A)
//   lights:                       # default: one point light at the box centre + 2 x its sides, L = 1
//     - {type: point, position: [600, 600, 600], intensity: 1, falloff: none}
//     - {type: directional, to_light: [0, 0, 1], intensity: [1, 0.9, 0.8]}
//   shadow: {method: march, step: 0, start_offset: 0.5, cache_build: sweep, cache_scale: 1}
//   acceleration: {ert_transmittance: 0, skip_empty: true, ess: multi_level, ess_test: range}
//                 # seed 001's ERT at 0.99 is ert_transmittance 0.01; ess: multi_level | one_level
//                 # (the source's); ess_test: range (exact) | voxel (the repo's)
//   traversal: {method: image_order, tile: 10, render_threads: 0, restrict_canvas: true, parallel: true}
//                 # object_order: seed 001's tiles x blocks renderer (a blocked layout); parallel:
//                 # false renders image order on one thread
//   rays: {method: analytic, camera_inside: reject}
//   output: {mode: standalone, background: [0, 0, 0], background_image: earth.png, exposure: 1}
//   timing: {warmup: 3, frames: 20}   # vlr.timing.protocol: frames rendered, the median reported
//   method: ray_casting           # ray_casting (the volume integrator) | slicing (seed 003: the
//                                 # `slicing:` section of slicing/slicing_scene.h; volume, camera,
//                                 # output and timing as above; the ray caster's model, sampling,
//                                 # optics, lights, shadow, acceleration, traversal and rays keys are
//                                 # refused with it)

#include <meltlab/render/camera.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/slicing/slicing_scene.h>
#include <meltlab/render/volume/clv_file.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/volume_io.h>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace meltlab {
class ConfigSection;
}

namespace meltlab::render {

/// The layout a scene renders (seed 001).
enum class VolumeLayout { kAsStored, kLinear, kBlocked };

/// Where a scene's volume comes from.
struct VolumeSource {
  std::optional<VolumeGenerateOptions> generate;  ///< generated (the seed's data) ...
  std::filesystem::path file;                     ///< ... or read (meltlab's .json header, .vdb or .clv)
  std::optional<Box3> box;                        ///< place the volume in this box (default: as stored)
  ClvMemory memory = ClvMemory::kMmap;            ///< .clv files
  ClvSamples samples = ClvSamples::kStored;       ///< stored numbers or float32 at load
  VolumeLayout layout = VolumeLayout::kAsStored;
  int block_side = 16;     ///< layout: blocked
  VolumeReadOptions read;  ///< .vlb, .nrrd, .nhdr: normalisation
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
  std::filesystem::path background_image;         ///< composite mode: the image behind the volume
  double exposure = 1.0;                          ///< PNG: colours times this, clamped to [0, 1]
  TfOutput tf_output = TfOutput::kPremultiplied;  ///< model transfer_function: the 8-bit image
  int warmup_frames = 0, timed_frames = 1;
  /// method: slicing (seed 003) — its settings; nullopt: the ray caster.
  std::optional<SlicingScene> slicing;
};

/// Reads a scene file; relative paths in it are taken from the scene's folder.
VolumeScene read_volume_scene(const std::filesystem::path& file);
/// The same from a section (the caller's finish() refuses unknown keys).
VolumeScene parse_volume_scene(const ConfigSection& section, const std::filesystem::path& base_dir);

/// The scene's volume: generated or read, placed in the scene's box (seed 000's generated volumes
/// default to the seed's 300-unit box centred at the origin). A blocked .clv file or layout is
/// refused here (load_scene_volumes).
Volume load_scene_volume(const VolumeScene& scene);

/// The scene's volume in the layout it asks for: `bricked` for a blocked layout (a .clv file in
/// blocks, or layout: blocked), else `dense`.
struct SceneVolume {
  Volume dense;
  BrickedVolume bricked;
  std::optional<ClvHeader> clv;                ///< the header of a .clv file
  std::optional<Normalisation> normalisation;  ///< a .vlb, .nrrd or .nhdr file: what its load did
  bool is_bricked() const { return !bricked.empty(); }
  Box3 domain() const { return is_bricked() ? bricked.domain() : dense.domain(); }
};
SceneVolume load_scene_volumes(const VolumeScene& scene);

/// Every clv.* parameter of a render with the transfer-function model (name/value text pairs).
std::vector<std::pair<std::string, std::string>> describe_clv(const VolumeScene& scene, const SceneVolume& volume);

/// Every vlr.* parameter of a render with its resolved value, as name/value text pairs in the
/// spec's order (written to the run record).
std::vector<std::pair<std::string, std::string>> describe_vlr(const VolumeScene& scene, const Volume& volume);

}  // namespace meltlab::render
