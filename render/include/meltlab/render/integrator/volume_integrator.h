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
//
// Seed 001 (Majer, CPU rendering of large volumes; spec ../shared/spec/cpu-large-volumes.md) adds
// an optical model, two storages and a traversal (render/src/integrator/volume_tf.cpp):
//   - the transfer-function model (OpticalModel::kTransferFunction): per sample a 1-D TF gives a
//     colour c (0-255) and an opacity α₀ (volume/transfer_function.h), α₀ is corrected for the step
//     (α = 1 - (1 - α₀)^{s/s₀}, or the thesis's printed s₀/s), c is Phong-shaded from the gradient
//     where |∇f| exceeds a threshold, and the samples are alpha-composited front to back
//     (C += (1 - A) α c, A += (1 - A) α) with early termination once A > 1 - ert_transmittance
//     (the source's 0.99 is ert_transmittance 0.01). The frame holds I = C/255 and T = 1 - A.
//   - storage: the linear layout (a Volume, e.g. a .clv file viewed z fastest in place, in RAM or
//     memory-mapped) or seed 001's blocks with a one-voxel overlap (BrickedVolume); both are read by
//     one lookup rule (the position clamped to the volume, the cell's lower corner min(⌊x⌋, N - 2)),
//     so the two layouts give bit-identical images.
//   - empty-space skipping: the source's one-level index (4³ cells, S + 1 voxels, a lookup per
//     sample, one step at a time) or the multi-level one (min/max per 4³ cell and 32³ region, TF-
//     independent; empty runs crossed in one jump on the same sample grid); both exact with the
//     range test (no pixel changes); per-block visibility for bricks.
//   - traversal: image order (per pixel, whole rays) or the source's object-order renderer for
//     bricks — tiles × blocks, each tile's blocks near to far, one task per tile in flight (a TBB
//     flow graph: render node and a serial compositor node), global ERT; the samples lie on each
//     ray's global grid t₀ + k s, so it is bit-identical to image order.

#include <meltlab/core/image.h>
#include <meltlab/render/camera.h>
#include <meltlab/render/volume/bricked_volume.h>
#include <meltlab/render/volume/transfer_function.h>
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
  kTransferFunction,    ///< seed 001: 1-D TF, opacity correction, Phong from gradients, alpha compositing
};

/// vlr.sampling.ds_rule.
enum class StepRule {
  kDiagonalOverN,  ///< Δs = (box diagonal) / n [4.6]: no ray gets more than n samples (the source)
  kFitSegment,     ///< per ray, ceil(length / step) equal steps (each ray's segment exactly covered)
  kFixedStep,      ///< seed 001: floor(length / step) whole steps from the entry, one sample each
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

/// clv.gradient.scheme (seed 001's shading), in value per voxel.
enum class GradientScheme {
  kCentral,   ///< (P(x + 1) - P(x - 1)) / 2 per axis, trilinear P, positions clamped (the thesis, n = 1)
  kOneSided,  ///< P(x) - P(x + 1) per axis (the repo; already pointing out of dense material)
};

/// Phong shading of the TF model (clv.shade.*): where |∇f| > threshold, with n̂ the outward normal,
/// L the light's propagation direction, r = L reflected about n̂ and v₋ towards the eye:
///   c' = c (max(n̂ · (-L), 0) + ka) + ks max(r · v₋, 0)^q (1, 1, 1)   (0-255 units).
struct TfShading {
  bool enabled = true;
  GradientScheme gradient = GradientScheme::kCentral;
  double threshold = 2.0;                                              ///< clv.shade.grad_threshold
  Eigen::Vector3d light_dir = -Eigen::Vector3d(4, 3, 2).normalized();  ///< L (the repo's static light)
  double ka = 0.16, q = 128, ks = 120;                                 ///< the repo's values
};

/// The transfer-function model (OpticalModel::kTransferFunction, seed 001).
struct TfModel {
  TransferFunction table = TransferFunction::shapes();  ///< clv.tf.table
  double reference_step = 0;                            ///< s₀ (scene units); 0 = one voxel (the smallest spacing)
  OpacityExponent exponent = OpacityExponent::kStepOverReference;  ///< clv.tf.opacity_exponent
  TfShading shading;
};

/// Empty-space skipping of the TF model (acceleration.skip_empty on).
enum class EmptySpaceScheme {
  kOneLevel,    ///< the source's EmptyIndex: the 4³ cell of every sample looked up, one step at a time
  kMultiLevel,  ///< min/max per 4³ cell and 32³ region: whole empty runs crossed in one jump
};
/// How a 4³ cell is found empty (clv.ess.index_test).
enum class EmptyCellTest {
  kRange,  ///< no value in the cell's [min, max] (S + 1 voxels) has α > 0: exact for any TF
  kVoxel,  ///< no voxel of the S + 1 has α > 0 (the repo): misses interpolated values between them
};
/// How rays traverse the volume (TF model).
enum class Traversal {
  kImageOrder,   ///< per pixel, the whole ray (TBB tiles when parallel)
  kObjectOrder,  ///< seed 001's tiles x blocks renderer with global ERT (bricked volumes only)
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
  // --- seed 001: the TF model, its empty-space skipping and traversal ---
  TfModel tf;
  EmptySpaceScheme ess = EmptySpaceScheme::kMultiLevel;
  EmptyCellTest ess_test = EmptyCellTest::kRange;
  Traversal traversal = Traversal::kImageOrder;
  int tile = 10;                      ///< clv.par.tile: tile side in pixels (object order)
  int render_threads = 0;             ///< clv.par.render_threads (object order; 0: every hardware thread)
  bool restrict_canvas = true;        ///< cast rays only inside the volume's projected rectangle
  bool record_sample_counts = false;  ///< per-pixel sample counts in VolumeFrame::sample_counts
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
  // --- the object-order traversal (seed 001) ---
  std::int64_t blocks_visible = 0;    ///< blocks of the volume visible under the TF (queued somewhere)
  std::int64_t block_tasks = 0;       ///< (tile, block) tasks rendered
  std::int64_t queue_empty = 0;       ///< tasks after which no other task was waiting for a render thread
  std::int64_t order_violations = 0;  ///< segments that arrived behind a later one of the same ray (0)
  double render_busy_ms = 0;          ///< summed time the render threads spent in tasks
};

/// A rendered frame: linear radiance I (3 channels) and the transmittance T (1 channel) of every
/// pixel; the pixel's colour over a background B is I + T · B.
struct VolumeFrame {
  ImageF radiance;       ///< RGB
  ImageF transmittance;  ///< T per pixel (1 where the ray missed the volume)
  VolumeRenderStats stats;
  std::vector<std::uint32_t> sample_counts;  ///< per pixel, row-major (record_sample_counts)
};

/// A shadow cache of one light: T to the light at the volume's samples (or a finer/coarser grid).
struct ShadowCache {
  Volume transmittance;  ///< float32, cell-centred or nodes as the volume, same domain
};

/// The integrator for callers that cast their own rays (the photo renderer of voxel ice, which
/// adds a ground behind the ice): the per-render state — empty-space macrocells, lights, shadow
/// caches — is built once, then rays are traced from any thread.
class VolumeRangeIndex;

class VolumeTracer {
 public:
  /// Throws InputError for bad settings. Builds the shadow caches unless given (one per light);
  /// for the TF model the empty-space index (from `ranges` when given, see build_range_index).
  VolumeTracer(const Volume& volume, const VolumeRenderSettings& settings, const std::vector<ShadowCache>& caches = {});
  VolumeTracer(const Volume& volume, const VolumeRenderSettings& settings,
               std::shared_ptr<const VolumeRangeIndex> ranges);
  /// A bricked volume: the TF model only (InputError otherwise).
  VolumeTracer(const BrickedVolume& volume, const VolumeRenderSettings& settings,
               std::shared_ptr<const VolumeRangeIndex> ranges = nullptr);
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
  /// A frame seen by the camera, with this state (render_volume builds a tracer and calls this).
  VolumeFrame render(const Camera& camera) const;
  const Box3& box() const;
  double cache_build_ms() const;
  std::int64_t cache_shadow_samples() const;
  /// Time spent building the TF model's empty-space flags and block visibility (0 for others).
  double index_build_ms() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The TF-independent part of the TF model's empty-space index: min and max of the stored values
/// over every 4³ cell's S + 1 = 5 voxels per axis, and over every block of a bricked volume. Build
/// it once per volume and share it between tracers with different TFs, switches or traversals.
class VolumeRangeIndex {
 public:
  static std::shared_ptr<const VolumeRangeIndex> build(const Volume& volume);
  static std::shared_ptr<const VolumeRangeIndex> build(const BrickedVolume& volume);
  virtual ~VolumeRangeIndex() = default;
  std::array<int, 3> dims() const { return dims_; }
  double build_ms() const { return build_ms_; }
  std::int64_t memory_bytes() const { return memory_bytes_; }

 protected:
  std::array<int, 3> dims_{0, 0, 0};
  double build_ms_ = 0;
  std::int64_t memory_bytes_ = 0;
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

/// The same for a bricked volume (the TF model; image or object order).
VolumeFrame render_volume(const BrickedVolume& volume, const Camera& camera, const VolumeRenderSettings& settings);
void check_volume_render_settings(const BrickedVolume& volume, const VolumeRenderSettings& settings);

/// clv.output.final_multiply: the 8-bit image of a TF frame over black, truncated as the source:
/// premultiplied (pixel = C, correct) or source_double (pixel = C·A, the source's double multiply).
enum class TfOutput { kPremultiplied, kSourceDouble };
Image8 tf_output_image(const VolumeFrame& frame, TfOutput output);

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
std::string ess_scheme_name(EmptySpaceScheme e);
std::string traversal_name(Traversal t);

}  // namespace meltlab::render
