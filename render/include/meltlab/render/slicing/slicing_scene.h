#pragma once
// The `slicing:` section of a `meltlab volume render` scene with `method: slicing` (read through
// core/config.h; every key a vsi.* choice of ../shared/spec/volume-slicing-importance.md §6 with
// the harness's default; the rest of the scene file — volume, camera, output, timing — is the ray
// caster's):
//
//   method: slicing
//   slicing:
//     mode: blend                 # blend | mip | combined (combined: the spec's interpretation)
//     quality_class: 1            # Δd = QC · h0
//     d_range: tight              # tight | conservative (the source's ±D)
//     blend_operator: over        # over | additive
//     opacity_correction: true
//     lit_blend: false            # vsi.shade.modes: Blinn-Phong in Blend too
//     value_range: [lo, hi]       # vsi.data.norm_source: the values mapped to [0, 1]; default scanned
//                                 # (a .vlb/.nrrd file: [0, 1], what its `normalise` at load mapped)
//     gradient: {radius: 2, neighbourhood: cube, bits: 8, cache: true}
//     light: {position_camera: [1, 1, 1], ambient: 0.2, diffuse: 0.7, specular: 0.3, exponent: 32, gate: 0}
//     mask:
//       resolution: [100, 100, 100]
//       edits:                    # normalised box coordinates [0, 1]³, applied in order
//         - {shape: box, centre: [0.5, 0.5, 0.8], size: [1.2, 1.2, 0.4], rotate_deg: [0, 0, 0], index: 0}
//         - {shape: sphere, centre: [0.4, 0.5, 0.5], radius: 0.1, index: 2}
//         - {shape: ellipsoid, centre: [...], radii: [a, b, c], rotate_deg: [...], index: 3}
//     transfer_functions:         # TF 1..4 (missing ones have α = 0); each piecewise linear:
//       - {name: tissue, points: [[0.2, 1, 0.8, 0.6, 0], [0.5, 1, 0.7, 0.5, 0.05]]}   # rows v, r, g, b, a
//       - {r: [[0, 1], [1, 1]], g: [[0, 0.2]], b: [[0, 0.1]], a: [[0.3, 0], [0.6, 0.8]]}  # per channel (x, y)
//     bloom: {enabled: false, contrast: 1, brightness: 0, gamma: 1, threshold: 0.7, sigma: 2, gain: 1}
//     tile: 16
//     parallel: true
//     skip_empty: true            # cells where no TF in use is visible are not fetched (same image)
//     skip_cell: 4                # edge of those cells in voxels: 2, 4, 8 or 16 (same image)
//     skip_voxels: true           # in live cells, samples whose voxel stencil no TF sees are not fetched (same image)
//     early_termination: 0        # Blend over only: > 0 composites front to back and stops at A >= it
//     exact_positions: false      # true: o + t_k v per sample (a division each) instead of g0 + j dg
//                                 # per ray; equal to float round-off (tested within 1e-5 voxel)
//     exact_pow: false            # true: std::pow for the corrected α and the specular power instead of
//                                 # slicing_pow / the float series (pixels equal up to round-off, tested)
//     simd: true                  # packets of 8 pixels on SIMD lanes; false: one ray at a time (the
//                                 # reference; the same image bit for bit, tested)

#include <meltlab/render/slicing/slicing_renderer.h>

#include <array>
#include <vector>

namespace meltlab {
class ConfigSection;
}

namespace meltlab::render {

struct SlicingScene {
  SlicingSettings settings;  ///< everything but the mask, which needs the volume's box
  bool mask = false;
  std::array<int, 3> mask_resolution{100, 100, 100};
  std::vector<MaskEdit> mask_edits;
  bool cache_gradients = true;
};

/// Reads the section (errors FILE:LINE; the caller's finish() refuses unknown keys).
SlicingScene parse_slicing_scene(const ConfigSection& section);

/// The scene's mask over a box (empty MaskVolume without a `mask:` section).
MaskVolume build_scene_mask(const SlicingScene& scene, const Box3& box);

}  // namespace meltlab::render
