#pragma once
// The references of seed 002's fog model (spec fog-spotlight-airlight.md §3; the thesis reports
// no accuracy at all, so "correct" is defined here) and the brute force a user would otherwise
// write (ray marching with uniform steps), the speed peer.
//
// R-air: eq. 3.7 integrated directly in x over [0, m] with the pointwise indicator I(θ(x)) of
// the light's profile (no intersection code) and a pointwise phase function (isotropic, or
// Henyey–Greenstein for extensions):
//   L_a = ∫_0^m Ω k_t p(cos α) I(θ(x)) e^{-k_t d}/d² e^{-k_t x} dx,  d = |x V̂ - S|,
// cos α = V̂·(X - S)/d... with the scattering angle between the light's propagation (X - S)/d and
// the way to the eye -V̂. Breakpoints at the foot point x = t and at the cone crossings, found by
// bisection on the indicator: along a line, D̂·(X - S)/|X - S| is unimodal (the direction from S
// sweeps half a great circle), so its maximum (closed form) splits [0, m] into two monotone parts
// with at most one crossing each per cone. Each lit piece by Boost.Math's adaptive Gauss–Kronrod
// 15/7 (relative 1e-10), confirmed by Boost.Math's tanh-sinh; accepted when the two agree to 1e-8.
//
// R-surf-model: eq. 3.19 by hemisphere quadrature with L_a from R-air along each ω_i under the
// model's own assumptions (no cone, a = 0, b = 50 mean free paths): Gauss–Legendre in φ (pole at
// the light) × uniform ψ, from 256×512, doubled until the relative change is below 1e-6. It
// isolates the G tables' error. R-surf-true: the same quadrature with the true cone segment of
// each ω_i (segment_in_cone), capped by occluders (a callback) and at 50 mean free paths; its
// L_a per direction is the analytic airlight with the accurate F (equal to R-air within 1e-9,
// tests/render/fog), 50× cheaper than R-air per direction. It measures the model's a = 0, b = ∞,
// cone-free assumption, which no table resolution can reduce.

#include <meltlab/render/fog/airlight.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace meltlab::render::fog {

struct RairOptions {
  double rel_tol = 1e-10;    ///< Gauss–Kronrod's relative tolerance (fsa.ref.tolerances)
  double accept_rel = 1e-8;  ///< the two rules must agree to this
  double hg_g = 0.0;         ///< Henyey–Greenstein g (0: isotropic, the model's phase)
};

struct RairResult {
  double value = 0;               ///< the Gauss–Kronrod value
  double confirm = 0;             ///< tanh-sinh's
  bool accepted = true;           ///< |value - confirm| <= accept_rel·|value| (or both below 1e-300)
  std::vector<double> knots;      ///< 0, the foot point, the crossings, m (sorted)
  std::vector<double> crossings;  ///< the indicator's crossings alone
};

/// R-air for one light along origin + s·V̂, s in [0, m] (m may be +∞), per unit colour ×
/// intensity (ring intensities included).
RairResult r_air(const Vec3& origin, const Vec3& view_dir, double m, const Spotlight& light, const FogMedium& medium,
                 const RairOptions& o = {});

/// The crossings of the cone θ_c (half-angle) of `light` with the ray, by bisection on the
/// indicator (as R-air finds them), sorted, in (0, m).
std::vector<double> indicator_crossings(const Vec3& origin, const Vec3& view_dir, double m, const Vec3& light_position,
                                        const Vec3& axis, double half_angle_rad);

/// A distance to the first occluder along origin + s·dir (+∞: none).
using OccluderFn = std::function<double(const Vec3& origin, const Vec3& dir)>;

struct SurfRefOptions {
  int n_phi = 256, n_psi = 512;  ///< the starting rule
  double rel_change = 1e-6;      ///< doubling stops when the total changes less than this
  int max_n_phi = 2048;          ///< and at the latest here (n_psi = 2 n_phi)
  double far_mfp = 50;           ///< b = ∞ as this many mean free paths
};

struct SurfRefResult {
  SurfaceTerms terms;  ///< fog_diffuse, fog_specular from the quadrature; direct terms analytic
  int n_phi = 0, n_psi = 0;
  double last_change = 0;  ///< relative change of the last doubling
};

/// R-surf-model at P (unit normal N̂ facing the eye, view_dir eye to P): L_p under the model's
/// assumptions, with L_a from R-air per φ node. Direct terms as in surface_terms.
SurfRefResult r_surf_model(const Vec3& p, const Vec3& normal, const Vec3& view_dir, const Spotlight& light,
                           const FogMedium& medium, const FogMaterial& material, const FogModelOptions& model = {},
                           const SurfRefOptions& o = {});

/// R-surf-true: the true cone segment per direction, capped by `occluder` (may be empty).
SurfRefResult r_surf_true(const Vec3& p, const Vec3& normal, const Vec3& view_dir, const Spotlight& light,
                          const FogMedium& medium, const FogMaterial& material, const OccluderFn& occluder,
                          const FogModelOptions& model = {}, const SurfRefOptions& o = {});

/// Uniform-step ray marching (midpoint rule, steps of at most step_m; m must be finite) of the
/// same integrand as R-air (isotropic): the brute force. `steps` receives the sample count.
double march_airlight(const Vec3& origin, const Vec3& view_dir, double m, const Spotlight& light,
                      const FogMedium& medium, double step_m, std::int64_t* steps = nullptr);

}  // namespace meltlab::render::fog
