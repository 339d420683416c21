#pragma once
// The volume integrator of meltlab: single-pass ray casting through a dense scalar volume with
// the optical models of seed 000 (spec ../shared/spec/volume-lighting-raycast.md): absorption
// [4.7], emission [4.8], emission–absorption [4.9], single scattering with a Henyey–Greenstein
// phase (HG, unshadowed) and with shadows marched towards every light ("HGAttenuated",
// [3.18] with [4.10]-[4.14]). Every volume renderer of meltlab runs its rays through this one
// integrator (the photo renderer of voxel ice, integrator/ice_photo, included); a new optical
// model is a new term here, not a second integrator.
//
// Per ray (world frame, scene units; ω the unit direction towards the viewer, the ray marched
// along v = -ω from the eye):
//   1. [t0, t1] = the ray inside the volume's domain box (slab test with the per-axis swap and the
//      miss test the source lacks; vlr.slab.swap) — or the two-pass entry/exit method.
//   2. samples t_i = t0 + offset + i Δs while t_i < t1 (vlr.sampling.*; Δs = diagonal / n),
//   3. at each: f = trilinear volume value, e = f^γ, σ = κ e (extinction), and the source
//        g = E + Σ_lights S,   E = C(x) e [κ],   S = a e [κ] L(x) p_HG(cos θ) [T_shadow],
//      brackets being the options vlr.emission.kappa_in_source, vlr.scatter.kappa_in_brdf and the
//      HGAttenuated shadow; cos θ = (light propagation direction) · (direction to the eye).
//   4. composited front to back by the chosen quadrature (vlr.quad):
//        inclusive (the source's listing): ext += e; T = exp(-κ Δs ext); I += g T [Δs]
//        exclusive:                        I += g T [Δs]; then T *= exp(-σ Δs)
//        exponential (exact for σ constant over a step): I += g T (1 - e^{-σ Δs})/σ; T *= e^{-σ Δs}
//      The emission model has no extinction (T = 1); the absorption model no source (g = 0).
//   5. pixel = I + T · background (standalone: the background colour; composite: an image).
// Beyond the source: early ray termination (stop once T < ert_transmittance; the error it
// causes is at most that T times the largest remaining radiance plus background), empty-space
// skipping (macrocells of 4³ samples where the volume is exactly 0 are crossed in one step on the
// same sample grid, so the image is bit for bit the same), jittered first offset, a shadow cache
// (transmittance to each light precomputed at the volume's samples once per light, then looked
// up trilinearly: HGAttenuated becomes O(n) per ray instead of O(n·m)), several lights, point
// and directional, with optional inverse-square falloff.
//
// Determinism: each pixel depends only on its own ray, so serial and parallel renders are
// bitwise identical.

#include <meltlab/core/image.h>
#include <meltlab/render/camera.h>
#include <meltlab/render/volume/volume.h>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::render {

using Rgb = Eigen::Vector3d;  ///< linear RGB (the alias of render_scene.h)

/// The optical models of seed 000 (§2.3).
enum class OpticalModel {
  kAbsorption,          ///< [4.7]: I = I0 exp(-κ ∫ f^γ)
  kEmission,            ///< [4.8]: I = I0 + ∫ C f^γ (no attenuation; added to the framebuffer)
  kEmissionAbsorption,  ///< [4.9]
  kHG,                  ///< [4.9] + HG single scattering, lights unshadowed (T'' = 1)
  kHGAttenuated,        ///< [3.18]: the same with the shadow transmittance T'' to every light
};

/// vlr.sampling.ds_rule.
enum class StepRule {
  kDiagonalOverN,  ///< Δs = (box diagonal) / n [4.6]: no ray gets more than n samples (the source)
  kFitSegment,     ///< per ray, ceil(length / step) equal steps (each ray's segment exactly covered)
};
/// vlr.sampling.first_offset: where the first sample lies past the entry point.
enum class FirstOffset {
  kZero,    ///< at the entry (the source)
  kHalf,    ///< half a step in (midpoint rule)
  kJitter,  ///< a per-pixel uniform fraction of a step (counter-based hash of seed and pixel)
};
/// vlr.quad: how each sample is composited (see the header comment).
enum class Quadrature { kInclusive, kExclusive, kExponential };

enum class LightType { kPoint, kDirectional };
/// vlr.light.falloff.
enum class LightFalloff { kNone, kInverseSquare };

struct VolumeLight {
  LightType type = LightType::kPoint;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();   ///< point light: world position
  Eigen::Vector3d to_light = Eigen::Vector3d::UnitZ();  ///< directional light: unit vector towards it
  Rgb intensity = Rgb::Ones();                          ///< L (radiance units of the image)
  LightFalloff falloff = LightFalloff::kNone;           ///< inverse square: L / distance² (point lights)
};

/// vlr.shadow.method (HGAttenuated).
enum class ShadowMethod {
  kMarch,  ///< march towards the light from every sample (the source: O(n·m) per ray)
  kCache,  ///< the transmittance to the light at the volume's samples, built once per light
};
/// How the shadow cache is built.
enum class ShadowCacheBuild {
  kSweep,  ///< layer by layer away from the light (O(samples)); a march per sample where it cannot
  kMarch,  ///< an exact shadow march from every sample (the cache's reference; O(samples · m))
};

/// vlr.raygen.method.
enum class RayGeneration {
  kAnalytic,  ///< the slab test per pixel ray (the source's timed method)
  kTwoPass,   ///< rasterised back faces, then front faces: S = F_f, v = F_b - F_f (for comparison)
};
/// vlr.camera.inside.
enum class CameraInside {
  kReject,      ///< an eye inside the volume's box is an error (the source renders nothing)
  kStartAtEye,  ///< rays start at the eye (t0 = 0)
};
/// vlr.emission.color_field.
enum class EmissionField {
  kConstant,  ///< C everywhere
  kRadial,    ///< C at the box centre to C_rim at the inscribed sphere's surface (a flame: yellow to red)
};

/// Every parameter of a render (the spec's vlr.* choices with their defaults).
struct VolumeRenderSettings {
  OpticalModel model = OpticalModel::kEmissionAbsorption;
  // --- sampling ---
  int samples = 100;  ///< vlr.sampling.n
  StepRule step_rule = StepRule::kDiagonalOverN;
  double step = 0;  ///< kFitSegment: the largest step (scene units); required > 0 for that rule
  FirstOffset first_offset = FirstOffset::kZero;
  std::uint64_t jitter_seed = 1;
  bool include_last_partial = false;  ///< vlr.sampling.last_partial: false = drop (the source's t < t1)
  Quadrature quadrature = Quadrature::kInclusive;
  // --- optics (Sabella's constants and the media) ---
  double kappa = 1.0;                 ///< κ: extinction per scene unit at f^γ = 1
  double gamma = 1.0;                 ///< γ: the data exponent
  bool emission_scale_by_ds = true;   ///< vlr.emission.scale_by_ds (inclusive/exclusive quadrature)
  bool kappa_in_source = false;       ///< vlr.emission.kappa_in_source
  bool kappa_in_brdf = false;         ///< vlr.scatter.kappa_in_brdf
  Rgb emission = Rgb(1.0, 0.6, 0.2);  ///< C
  EmissionField emission_field = EmissionField::kConstant;
  Rgb emission_rim = Rgb(0.8, 0.1, 0.0);  ///< C at the rim (kRadial)
  double albedo = 0.9;                    ///< a
  double hg_c = 0.5;                      ///< HG asymmetry c ∈ (-1, 1); c > 0 forward
  std::vector<VolumeLight> lights;        ///< empty: one point light at the spec's default
  /// HG models: a uniform ambient radiance (sky, room) in-scattered with ∫ p dω = 1, unshadowed:
  /// S += a e [κ] ambient — a stand-in for multiple scattering (the photo renderer's sky). 0: none.
  Rgb ambient = Rgb::Zero();
  // --- shadows (HGAttenuated) ---
  ShadowMethod shadow = ShadowMethod::kMarch;
  double shadow_step = 0;            ///< vlr.shadow.step (scene units); 0 = Δs (the primary step)
  double shadow_start_offset = 0.5;  ///< vlr.shadow.start_offset, a fraction of the shadow step
  ShadowCacheBuild shadow_cache_build = ShadowCacheBuild::kSweep;
  double shadow_cache_scale = 1.0;  ///< cache samples per volume sample along each axis
  // --- acceleration ---
  double ert_transmittance = 0.0;                 ///< stop a ray once T falls below this (0: never)
  bool skip_empty = true;                         ///< empty-space skipping (changes no pixel)
  VolumeAddress address = VolumeAddress::kClamp;  ///< vlr.tex.address
  // --- rays and output ---
  RayGeneration ray_generation = RayGeneration::kAnalytic;
  CameraInside camera_inside = CameraInside::kReject;
  Rgb background = Rgb::Zero();  ///< standalone: the colour behind the volume
  bool parallel = true;          ///< tiles in parallel (TBB); the image is the same either way
};

/// The spec's default light for a box: a point light at (2 d0, 2 d1, 2 d2) from the box centre,
/// L = 1 (vlr.light.*).
VolumeLight default_light(const Box3& box);

/// The Henyey–Greenstein phase function [4.14], normalised over the sphere:
/// (1/4π) (1 - c²) / (1 + c² - 2 c cosθ)^{3/2}.
double henyey_greenstein(double cos_theta, double c);

/// [t0, t1] of the ray o + t v inside the box (slab method with the per-axis swap; an axis with
/// v = 0 needs o within its slab); nullopt on a miss (t0 > t1) or when the box is behind
/// (t1 < 0). t0 may be negative (the origin inside the box).
struct RayInterval {
  double t0 = 0, t1 = 0;
};
std::optional<RayInterval> intersect_box(const Box3& box, const Eigen::Vector3d& o, const Eigen::Vector3d& v);

/// The two-pass method's rays (spec §2.4): the box's back faces and then its front faces are
/// rasterised (pixel centres, top-left rule, per triangle); per pixel covered by both, the ray
/// is S = F_f, v = F_b - F_f with t ∈ [0, 1]. `front` / `back` say which pass covered a pixel;
/// pixels covered by one pass only are the source's silhouette artefacts.
struct TwoPassRays {
  int width = 0, height = 0;
  std::vector<Eigen::Vector3d> entry, exit;  ///< F_f and F_b per pixel (row-major)
  std::vector<std::uint8_t> front, back;     ///< coverage of each pass
};
TwoPassRays two_pass_rays(const Box3& box, const Camera& camera);

/// Counters of one render.
struct VolumeRenderStats {
  std::int64_t rays = 0;                 ///< pixel rays that met the box
  std::int64_t samples = 0;              ///< primary samples evaluated (skipped empty samples not counted)
  std::int64_t skipped = 0;              ///< primary samples crossed by empty-space skipping
  std::int64_t shadow_samples = 0;       ///< volume samples taken by shadow marches (rendering and cache)
  std::int64_t terminated = 0;           ///< rays stopped by early ray termination
  std::int64_t silhouette_mismatch = 0;  ///< two-pass: pixels covered by one pass only
  double shadow_cache_ms = 0;            ///< time to build the shadow caches
  double render_ms = 0;                  ///< time of the ray casting itself
};

/// A rendered frame: linear radiance I (3 channels) and the transmittance T (1 channel) of every
/// pixel; the pixel's colour over a background B is I + T · B.
struct VolumeFrame {
  ImageF radiance;       ///< RGB
  ImageF transmittance;  ///< T per pixel (1 where the ray missed the volume)
  VolumeRenderStats stats;
};

/// A shadow cache of one light: T to the light at the volume's samples (or a finer/coarser grid).
struct ShadowCache {
  Volume transmittance;  ///< float32, cell-centred or nodes as the volume, same domain
};

/// The integrator for callers that cast their own rays (the photo renderer of voxel ice, which
/// adds a ground behind the ice): the per-render state — empty-space macrocells, lights, shadow
/// caches — is built once, then rays are traced from any thread.
class VolumeTracer {
 public:
  /// Throws InputError for bad settings. Builds the shadow caches unless given (one per light).
  VolumeTracer(const Volume& volume, const VolumeRenderSettings& settings, const std::vector<ShadowCache>& caches = {});
  ~VolumeTracer();
  VolumeTracer(const VolumeTracer&) = delete;
  VolumeTracer& operator=(const VolumeTracer&) = delete;

  struct Result {
    Rgb radiance = Rgb::Zero();  ///< I: what the volume adds along the ray
    double transmittance = 1.0;  ///< T: what it lets through from behind
    bool met = false;            ///< the ray met the volume's box before t_max
  };
  /// The ray o + t d (d unit) through the volume, on [max(entry, 0), min(exit, t_max)].
  /// `pixel_id` seeds the jittered first offset; counters go to `stats` if given (one per thread).
  Result trace(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max = 1e300, std::uint64_t pixel_id = 0,
               VolumeRenderStats* stats = nullptr) const;
  /// Transmittance from x along unit direction d to the box exit (or max_distance if nearer): the
  /// exact shadow march of the settings (shadow step, start offset, empty-space skipping).
  double transmittance(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double max_distance = 1e300,
                       VolumeRenderStats* stats = nullptr) const;
  const Box3& box() const;
  double cache_build_ms() const;
  std::int64_t cache_shadow_samples() const;

 private:
  friend VolumeFrame render_volume(const Volume&, const Camera&, const VolumeRenderSettings&,
                                   const std::vector<ShadowCache>&);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Throws the InputError render_volume would throw for these settings (checked before any work).
void check_volume_render_settings(const Volume& volume, const VolumeRenderSettings& settings);

/// Renders the volume seen by the camera. Throws InputError for bad settings (n < 1, κ < 0, γ <= 0,
/// c outside (-1, 1), a light inside the box for the cache, the eye inside the box with
/// CameraInside::kReject, ...) naming the parameter.
VolumeFrame render_volume(const Volume& volume, const Camera& camera, const VolumeRenderSettings& settings);

/// The same with the shadow caches given (one per light, from build_shadow_cache; they are built
/// inside render_volume when absent). Lets a sequence of frames reuse them while only the camera moves.
VolumeFrame render_volume(const Volume& volume, const Camera& camera, const VolumeRenderSettings& settings,
                          const std::vector<ShadowCache>& caches);

/// The shadow cache of light `light_index` of the settings (its lights, or the default light).
ShadowCache build_shadow_cache(const Volume& volume, const VolumeRenderSettings& settings, int light_index,
                               VolumeRenderStats* stats = nullptr);

/// The transmittance from world point x to light `light_index` by the exact shadow march of the
/// settings (the reference the cache is measured against).
double shadow_transmittance(const Volume& volume, const VolumeRenderSettings& settings, int light_index,
                            const Eigen::Vector3d& x);

/// The pixel colours I + T · B over a background colour.
ImageF composite_over(const VolumeFrame& frame, const Rgb& background);
/// The pixel colours I + T · B over a background image of the frame's size (3 channels).
ImageF composite_over(const VolumeFrame& frame, const ImageF& background);

/// The resolved step of a render (Δs for kDiagonalOverN; the largest step for kFitSegment).
double primary_step(const Volume& volume, const VolumeRenderSettings& settings);
/// The lights a render uses (the settings' lights, or the default light).
std::vector<VolumeLight> effective_lights(const Volume& volume, const VolumeRenderSettings& settings);

/// Names of the enum values as written in scene files and run records.
std::string optical_model_name(OpticalModel m);
std::string quadrature_name(Quadrature q);

}  // namespace meltlab::render
