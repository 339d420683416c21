#pragma once
// Photo-like renderer of a (melting) ice body on a dark textured ground, seen by a real
// camera: for validating contour extraction and fitting against a known truth.
//
// Optical model (spec ../shared/spec/volume-lighting-raycast.md §2.2-2.4, [3.14]/[3.18]):
// emission–absorption with single scattering of one directional lamp (Henyey–Greenstein
// phase, shadowed: "HGAttenuated") plus an isotropic uniform sky, through the voxel ice;
// behind it a Lambertian ground plane z = ground_z_m.
//   extinction   σ(X) = extinction_per_m · f(X),  f = IceFraction::sample (trilinear), γ = 1
//   in-scatter   S(X) = a · σ(X) · (L · p_HG(cosθ) · T_lamp(X) + sky)      (κ in the BRDF, [3.8];
//                the sky term is a uniform radiance in-scattered with ∫p dω = 1, unshadowed —
//                a crude stand-in for multiple scattering and room light that makes ice bright)
//   ground       I_g = ρ(x, y) · (L/π · cos θ_lamp · T_lamp(ground) + sky · T_zenith(ground))
//   pixel        I = I_g · T_view + Σ_segments T'(s) · S/σ · (1 - e^{-σ Δs})
// Phase convention (vlr.phase.cos_convention): cosθ = (lamp propagation direction) · (direction to
// the eye) = to_lamp · ray_direction; the camera looking down on a lamp from above sees
// back-scatter (cosθ = -cos θ_lamp); g > 0 is forward scattering.
// Quadrature: the segment [entry, min(exit, ground)] of the ray inside the (tight) box of the ice
// is split into n = ceil(length / step_m) equal steps, σ is sampled at each step's midpoint and
// the step is integrated exactly for that constant σ (the exponential integrator above), so a
// homogeneous medium is rendered exactly: the slab of thickness d over ground gives
// I_g · exp(-σ d) to rounding. T_lamp inside the ice is either marched per sample
// (Shadow::kMarch, exact for homogeneous media, O(n²) per ray) or read (trilinearly) from a
// per-render light-transmittance grid at the cell centres (Shadow::kGrid, default; built by one
// sweep layer by layer away from the lamp, Simpson's rule per layer, O(cells)). Ground shadows
// are always marched (one ray per pixel).
// Acceleration (skip_empty_space, default on) changes no sample position or value: the marches
// leave out only samples where the trilinear f is exactly 0 (blocks of 4³ cells with no non-zero
// cell within one cell of them are crossed in one step; cells with no non-zero neighbour are not
// interpolated), and the zenith ground shadow is the bilinear interpolant of per-column sums
// (the same sum up to rounding). Images equal those without it to float rounding (in practice
// bit for bit).
//
// Image chain (render_ice_photo): linear radiance (k x k stratified samples per pixel, averaged)
// → × exposure → Gaussian lens blur (sigma px) → gamma encoding (v = clamp(x)^(1/gamma)) →
// + Gaussian sensor noise (noise_sigma 8-bit levels, per pixel and channel from a counter-based
// hash of (seed, pixel, channel): deterministic, identical serial/parallel) → 8-bit BGR.
// JPEG compression is left to the caller (write_jpeg).
//
// Units: metres, z up, world frame of the camera (render/camera.h). Colours are RGB triples in
// the options; images are BGR (OpenCV order).

#include <meltlab/render/camera.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/sim/physics/ice_fraction.h>

#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <filesystem>

namespace meltlab::render {

struct IcePhotoOptions {
  // --- ice ---
  double extinction_per_m = 150.0;                      ///< σ at solid fraction 1 (bubbly ice: 5 mm → e^-0.75)
  double albedo = 0.99;                                 ///< single-scattering albedo a
  std::array<double, 3> ice_tint_rgb{0.96, 0.98, 1.0};  ///< multiplies a per channel
  double hg_g = 0.2;                                    ///< Henyey–Greenstein asymmetry, in (-1, 1)
  // --- light ---
  Vec3d to_lamp = Vec3d(0.35, 0.25, 0.9);  ///< direction towards the (directional) lamp; z > 0; normalised
  double lamp_irradiance = 1.0;            ///< L: irradiance normal to the beam (relative units)
  double sky_radiance = 0.25;              ///< uniform ambient radiance (sky, room)
  // --- ground ---
  double ground_z_m = 0.0;
  double ground_albedo = 0.05;  ///< dark absorbent cloth
  std::array<double, 3> ground_tint_rgb{1.0, 0.95, 0.9};
  double ground_texture_contrast = 0.5;   ///< ρ = albedo · (1 + contrast · n(x, y)), n ∈ [-1, 1]
  double ground_texture_scale_m = 0.003;  ///< feature size of the texture (fBm value noise)
  std::uint64_t ground_seed = 1;
  // --- camera / sensor ---
  double exposure = 3.0;            ///< linear radiance → [0, 1] sensor scale
  double gamma = 2.2;               ///< encoding gamma
  double lens_blur_sigma_px = 0.7;  ///< 0 = none
  double noise_sigma = 2.0;         ///< 8-bit levels, 0 = none
  std::uint64_t seed = 1;           ///< sensor noise seed
  int supersample = 1;              ///< k x k stratified samples per pixel
  // --- integrator ---
  double step_m = 0.0;  ///< primary (and shadow) step; 0 = h/2
  enum class Shadow { kGrid, kMarch, kNone };
  Shadow shadow = Shadow::kGrid;    ///< kNone: T_lamp = T_zenith = 1 everywhere
  double min_transmittance = 1e-5;  ///< a ray stops once its transmittance falls below this
  bool parallel = true;             ///< rows in parallel (TBB); the result is identical either way
  /// Skip blocks of the grid where the ice fraction is 0 (and its trilinear interpolant too) a
  /// block at a time; the samples taken and their values are unchanged, so is the result.
  bool skip_empty_space = true;
  /// The ice body's surface is the ½ level of the solid fraction (as in the solver and the
  /// true outline); partially filled cells are not a dilute fog. Before rendering, cell
  /// values are remapped to clamp((f - ½) / w + ½, 0, 1), so extinction rises from 0 to σ
  /// within ±w/2 of the interface. 0 renders the fraction as is (a dilute medium, the
  /// integrator's analytic tests). Without it the visible outline of a coarse grid lies
  /// ~1 cell outside the true one (P ≈ 0.2 at 4 mm voxels).
  double interface_width = 0.1;
};

/// Relative ground albedo modulation n(x, y) ∈ [-1, 1] (deterministic fBm value noise).
double ground_texture(double x_m, double y_m, double scale_m, std::uint64_t seed);

/// Linear radiance image, CV_32FC3 (BGR), before exposure, blur, noise and quantisation.
/// `only` (optional CV_8UC1 of the image size): pixels where it is 0 are not traced (left 0),
/// e.g. outside the ice's outline when the caller composites the bare ground there.
cv::Mat render_ice_radiance(const sim::physics::IceFraction& ice, const Camera& camera,
                            const IcePhotoOptions& options = {}, const cv::Mat& only = cv::Mat());

/// The sensor chain applied to a linear radiance image (see the header comment): CV_8UC3 BGR.
cv::Mat develop_photo(const cv::Mat& radiance, const IcePhotoOptions& options = {});

/// render_ice_radiance + develop_photo: an 8-bit BGR "photo".
cv::Mat render_ice_photo(const sim::physics::IceFraction& ice, const Camera& camera,
                         const IcePhotoOptions& options = {});

/// Ground-truth outline: CV_8UC1, 255 where the pixel-centre ray meets a point with ice
/// fraction ≥ `threshold` before the ground plane (sampled every h/8 along the ray, inside the
/// box of cells that can reach the threshold).
cv::Mat ice_true_mask(const sim::physics::IceFraction& ice, const Camera& camera, double threshold = 0.5,
                      double ground_z_m = 0.0);

/// Writes an 8-bit BGR (or gray) image as JPEG with `quality` (1..100) through meltlab's
/// write_image (the format follows the extension: name the file .jpg), atomically. Throws
/// InputError on failure.
void write_jpeg(const std::filesystem::path& file, const cv::Mat& image, int quality = 90);

}  // namespace meltlab::render
