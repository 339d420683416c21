#pragma once
// Seed 003's procedural CT phantom (spec volume-slicing-importance.md §3, vsi.testgen): nested
// ellipsoids with the Hounsfield values of the source's Table 1 (air -1000, fat -120, water 0,
// muscle 40, bone 1000), generated at 256 x 256 x 113 with spacing (1, 1, 2) as int16 (the VLB
// example's CT head), always available in place of a real CT.
//
// Geometry (node samples; p is the offset from the box centre c = (n - 1)/2 · spacing, L =
// (n - 1) · spacing the box's sides; every length below is a fraction of L per axis):
//   skin surface   ellipsoid E0, semi-axes a0 = (0.45, 0.40, 0.50) (the spec's "0.45 x 0.4 x 0.5
//                  of the box", read as semi-axes: the head fills the box as a CT head does)
//   fat            between E0 and E1, a1 = a0 - 0.02 (the skin layer: the spec gives no thickness)
//   bone shell     between E1 and E2, a2 = a1 - 0.03 (the spec's shell thickness 0.03)
//   water          inside E2 (brain: water-equivalent tissue), except
//   two muscles    semi-axes (0.07, 0.12, 0.15) at (±0.20, +0.05, -0.05): 40 HU
//   two cavities   semi-axes (0.05, 0.05, 0.06) at (±0.08, -0.25, -0.10): air (sinuses)
//   air            outside E0
// "Inside" an ellipsoid means Σ (p_a / (a_a L_a))² < 1; the inner structures lie wholly inside E2
// and do not overlap. The geometry is mirror-symmetric in x: p_x = (i - (n_x - 1)/2) · h_x is
// exact in double arithmetic, so sample i and n_x - 1 - i see the same noise-free value bit for bit.
// Noise: additive Gaussian (σ = 20 HU by default), per sample from a counter-based generator
// (splitmix64 of the seed and the sample index, Box-Muller), so the volume depends on the seed
// only, not on the thread count. Samples are rounded to the nearest integer and clamped to int16.

#include <meltlab/render/volume/scalar_volume.h>

#include <array>
#include <cstdint>
#include <map>
#include <string>

namespace meltlab::render {

/// Hounsfield units of the source's Table 1.
namespace hu {
inline constexpr double kAir = -1000, kFat = -120, kWater = 0, kMuscle = 40, kBone = 1000;
}

struct CtPhantomOptions {
  std::array<int, 3> dims{256, 256, 113};
  Eigen::Vector3d spacing{1.0, 1.0, 2.0};
  double noise_sigma_hu = 20.0;  ///< 0: the noise-free phantom
  std::uint64_t seed = 1;
};

/// The noise-free value (HU) at an offset from the box centre, in scene units, for a box of sides L.
double ct_phantom_hu(const Eigen::Vector3d& p_from_centre, const Eigen::Vector3d& box_sides);

/// The phantom as int16 samples (origin 0, the options' spacing). Throws InputError for dims < 2
/// on an axis, a non-positive spacing or a negative/non-finite σ.
ScalarVolume generate_ct_phantom(const CtPhantomOptions& options);

/// The parameters as name/value text (for generator records and run records).
std::map<std::string, std::string> describe_ct_phantom(const CtPhantomOptions& options);

}  // namespace meltlab::render
