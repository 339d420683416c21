#pragma once
// Seed 002's analytic single scattering of spotlights in homogeneous fog (spec
// fog-spotlight-airlight.md §2): the airlight along a view ray and the surface terms, per light,
// with F and G from tables (the fast path) or from the accurate routines (for the tests).
//
// Frame and units: world frame, metres; a ray starts at `origin` (the eye) with unit direction
// V̂ and ends at the visible surface at distance m (m = +∞: nothing hit). Radiance per unit of
// the light's intensity I (W/sr, arbitrary scale); colours are linear RGB.
//
// Airlight of one cone over the lit segment [a, b] (eq. 3.13-3.17):
//   L_a = A0 [F(A1, v_b) - F(A1, v_a)],  A0 = Ω k_t I e^{-k_t t} / (2π h),  A1 = k_t h,
//   v_x = π/4 + ½ atan((x - t)/h),  v_∞ = π/2,
// with l = |S|, t = S·V̂ (eye to the foot point; negative when the light is behind the eye),
// h = |S × V̂| (light to the ray), clamped to h >= fsa.h_min·l (the integral diverges as 1/h
// when the ray passes through the light). Nested cones θ_1 < θ_2 < ... with ring intensities
// I_k: L_a = Σ_k (I_k - I_{k+1}) L_a^{cone θ_k}. A point light (Sun et al. 2005) is the segment
// [0, m]: A0 [F(A1, v_m) - F(A1, φ/2)].
//
// Surface at P with unit normal N̂ (facing the eye), light at distance l = |S - P| in direction L̂,
// mirrored view direction R̂ (eq. 3.24, f_r = k_d: no 1/π, fsa.brdf.lambert_norm):
//   L_p = I k_d [e^{-k_t l} cos θ_s / l² + Ω k_t/(2π l) G_0(k_t l, θ_s)]
//       + I k_s [e^{-k_t l} cos^n θ_s' / l² + Ω k_t/(2π l) G_n(k_t l, θ_s')],
//   cos θ_s = N̂·L̂, cos θ_s' = R̂·L̂ (direct terms clamped at 0), G_0 = the table of exponent 1.
// fsa.surface.only_in_cone (default, as the listing): the surface terms only where P is lit;
// I = the intensity of P's ring. The radiance reaching the eye is L_p e^{-k_t m}
// (fsa.surface.view_attenuation = apply) or L_p (source_omit, the listing).

#include <meltlab/render/fog/cone.h>
#include <meltlab/render/fog/fog_tables.h>

#include <Eigen/Core>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace meltlab::render::fog {

using Rgb = Eigen::Vector3d;

/// The homogeneous medium (fsa.medium.*).
struct FogMedium {
  double kt = 0.04;     ///< extinction coefficient k_t, 1/m (fsa.medium.kt)
  double albedo = 1.0;  ///< Ω: scattering = Ω k_t (fsa.medium.albedo; the source: Ω = 1)
};

/// One ring of a stepped profile: intensity `intensity` (relative) for θ up to `half_angle_rad`.
struct ConeStep {
  double half_angle_rad = 0.5235987755982988;  ///< 30°
  double intensity = 1.0;
};

enum class LightKind {
  kSpot,   ///< cones (seed 002)
  kPoint,  ///< isotropic point light (Sun et al. 2005; the S3 comparison)
};

struct Spotlight {
  LightKind kind = LightKind::kSpot;
  Vec3 position = Vec3(0, 0, 5);  ///< world, m
  Vec3 axis = Vec3(0, 0, -1);     ///< unit spot direction (normalised on use)
  /// Rings by increasing half-angle (< π); one step = a single hard cone (fsa.light.profile).
  std::vector<ConeStep> profile{ConeStep{}};
  Rgb colour = Rgb(1, 1, 1);  ///< fsa.light.color: RGB × intensity
  double intensity = 1.0;

  /// The relative intensity at angle θ from the axis (0 outside the outermost cone; 1 for a point light).
  double intensity_at(double theta_rad) const;
  /// The ring intensity at world point x.
  double intensity_at(const Vec3& x) const;
};

/// The constants of one light that every pixel of a frame shares — the unit axis and, per ring,
/// cos θ_k and the weight I_k - I_{k+1} of the nested cones — so that a pixel takes no cosine
/// and no normalisation: prepare once per frame (fog_frame, FogShader), shade many pixels. The
/// Spotlight overloads below prepare per call (the same numbers, bit for bit).
struct PreparedLight {
  Spotlight light;
  Vec3 axis = Vec3(0, 0, -1);    ///< light.axis normalised
  std::vector<double> cos_half;  ///< cos of each ring's half-angle
  std::vector<double> weight;    ///< I_k - I_{k+1} (I past the last ring: 0)

  explicit PreparedLight(const Spotlight& l);
  /// The ring intensity at world point x (Spotlight::intensity_at(x) prepares and calls this).
  double intensity_at(const Vec3& x) const;
};
std::vector<PreparedLight> prepare_lights(const std::vector<Spotlight>& lights);

/// Which F/G a model evaluation uses: the tables (the fast path) or, where a pointer is null,
/// the accurate routines (airlight_f_between, surface_g).
struct FogFunctions {
  const FogTable* f = nullptr;
  /// If set, the airlight uses the H table instead of F (fsa.table.function = H):
  ///   L_a = Ω k_t I/(2π h) [e^{-k_t(a + d_a)} H(A1, v_a) - e^{-k_t(b + d_b)} H(A1, v_b)],
  /// d_x = √(h² + (x - t)²) the light's distance from the point at x: the same integral as
  /// A0 [F(A1, v_b) - F(A1, v_a)] without subtracting two nearly equal F values times a large
  /// e^{-k_t t} (a light behind the eye, a segment far from the foot point).
  const FogTable* h = nullptr;
  const FogTable* g_diffuse = nullptr;   ///< exponent 1 (G_0)
  const FogTable* g_specular = nullptr;  ///< exponent n (G_n)
};

/// How often a table lookup fell beyond its domain (fsa.table.beyond_domain: clamp, flag).
struct LookupCounts {
  std::int64_t lookups = 0, clamped = 0;
  LookupCounts& operator+=(const LookupCounts& o) {
    lookups += o.lookups;
    clamped += o.clamped;
    return *this;
  }
};

enum class ViewAttenuation { kApply, kSourceOmit };
enum class ConeSolver { kRobust, kSource };
enum class SpecularArgs {
  kMirror,  ///< θ_s' = ∠(mirror of the view about N, light) (fsa.errata.specular_args: fixed)
  kSource,  ///< the listing: the specular call gets N·L and θ_s
};

/// The open choices of spec §7 that the model evaluation reads (the table ones: TableOptions).
struct FogModelOptions {
  ViewAttenuation view_attenuation = ViewAttenuation::kApply;       ///< fsa.surface.view_attenuation
  ConeSolver cone_solver = ConeSolver::kRobust;                     ///< fsa.cone.solver
  SpecularArgs specular_args = SpecularArgs::kMirror;               ///< fsa.errata.specular_args
  bool surface_only_in_cone = true;                                 ///< fsa.surface.only_in_cone
  double h_min_rel = 1e-4;                                          ///< fsa.h_min (× l)
  bool airlight = true, surface_direct = true, surface_fog = true;  ///< terms (for figures: Fig. 5.2 b/c)
};

/// Per-ray light geometry: l = |S|, t = S·V̂, h = max(|S × V̂|, h_min l).
struct RayLight {
  double l = 0, t = 0, h = 0;
};
RayLight ray_light(const Vec3& view_dir, const Vec3& light_rel, double h_min_rel);

/// v_x = π/4 + ½ atan((x - t)/h) (π/2 for x = +∞).
double airlight_v(const RayLight& g, double x);

/// The airlight of a unit intensity over [a, b] (0 <= a <= b <= ∞) of the ray (eq. 3.17).
double airlight_interval(const RayLight& g, const FogMedium& medium, double a, double b, const FogFunctions& fn,
                         LookupCounts* counts = nullptr);

/// The airlight of one light along the ray origin + s·V̂, s in [0, m], per unit of colour ×
/// intensity (the rings' relative intensities included).
double airlight_unit(const Vec3& origin, const Vec3& view_dir, double m, const Spotlight& light,
                     const FogMedium& medium, const FogFunctions& fn, const FogModelOptions& o,
                     LookupCounts* counts = nullptr);
double airlight_unit(const Vec3& origin, const Vec3& view_dir, double m, const PreparedLight& light,
                     const FogMedium& medium, const FogFunctions& fn, const FogModelOptions& o,
                     LookupCounts* counts = nullptr);

/// Sun et al.'s point-light airlight A0 [F(A1, v_m) - F(A1, φ/2)] (φ from acos, as the paper).
double airlight_point_sun(const Vec3& origin, const Vec3& view_dir, double m, const Vec3& light_position,
                          const FogMedium& medium, const FogFunctions& fn, double h_min_rel = 1e-4);

/// A Phong material (eq. 3.24): k_d (times an RGB colour), k_s, exponent n (fsa.brdf.phong_n).
struct FogMaterial {
  double kd = 0.7, ks = 0.3;
  int n = 20;
  Rgb diffuse_colour = Rgb(1, 1, 1);
};

/// The four surface terms per unit intensity (I of P's ring included).
struct SurfaceTerms {
  double direct_diffuse = 0, fog_diffuse = 0, direct_specular = 0, fog_specular = 0;
  double diffuse() const { return direct_diffuse + fog_diffuse; }
  double specular() const { return direct_specular + fog_specular; }
};

/// L_p at P (normal N̂ facing the eye) seen along view_dir (eye to P, unit); zero terms where
/// only_in_cone and P is not lit.
SurfaceTerms surface_terms(const Vec3& p, const Vec3& normal, const Vec3& view_dir, const Spotlight& light,
                           const FogMedium& medium, const FogMaterial& material, const FogFunctions& fn,
                           const FogModelOptions& o, LookupCounts* counts = nullptr);
SurfaceTerms surface_terms(const Vec3& p, const Vec3& normal, const Vec3& view_dir, const PreparedLight& light,
                           const FogMedium& medium, const FogMaterial& material, const FogFunctions& fn,
                           const FogModelOptions& o, LookupCounts* counts = nullptr);

/// A visible surface point for fog_radiance.
struct SurfaceHit {
  Vec3 p = Vec3::Zero(), normal = Vec3::UnitZ();
  const FogMaterial* material = nullptr;
};

/// Everything one pixel gets from the lights in fog: Σ_lights airlight + surface terms × the
/// view attenuation (`surface` = nullptr: the ray sees nothing within m).
Rgb fog_radiance(const Vec3& origin, const Vec3& view_dir, double m, const SurfaceHit* surface,
                 const std::vector<Spotlight>& lights, const FogMedium& medium, const FogFunctions& fn,
                 const FogModelOptions& o, LookupCounts* counts = nullptr);
Rgb fog_radiance(const Vec3& origin, const Vec3& view_dir, double m, const SurfaceHit* surface,
                 const std::vector<PreparedLight>& lights, const FogMedium& medium, const FogFunctions& fn,
                 const FogModelOptions& o, LookupCounts* counts = nullptr);

/// The options as "fsa.*" lines for the run record.
std::vector<std::pair<std::string, std::string>> describe_options(const FogModelOptions& o);

}  // namespace meltlab::render::fog
