#pragma once
// Seed 003's slicing renderer (spec ../shared/spec/volume-slicing-importance.md §2.4-§2.7): the
// view-aligned plane stack of slice_geometry.h sampled per pixel back to front (vsi.cpu.realisation:
// per-pixel ray-plane intersection, the same samples as rasterising the polygons), classified by
// the mask volume and four transfer functions, composited by Blend, MIP or the combined mode, lit
// by Blinn-Phong from the gradient volume, then the bloom chain. It is a second sampling strategy
// for the integrand of the one volume integrator's TF model (integrator/volume_integrator.h): the
// same Volume, trilinear lookups, TF concept (volume/transfer_function.h) and opacity correction
// (corrected_opacity); only the sample positions (planes instead of t0 + k Δs) and the back-to-front
// order differ. slicing_test checks that Blend converges to the ray caster's image as QC → 0.
//
// Per pixel (ray o + t v from the eye, v unit; planes k back to front, t_k from ray_slices):
//   x = o + t_k v; m = mask(x) (nearest); m == 0: skip (cut away)
//   f̂ = (f(x) - lo) / (hi - lo)  (f trilinear; vsi.data.norm_source: lo, hi given, default the
//        volume's scanned extrema)
//   (c, a) = TF_m(f̂); a == 0: skip
//   a' = 1 - (1 - a)^(Δ / h0), Δ = Δd / cos ψ the spacing along this ray (vsi.blend.opacity_correction)
//   c_lit = Blinn-Phong(c, n̂) in MIP and combined (and Blend with lit_blend); n̂ = -normalise(g'
//        / spacing) with g' the decoded, trilinearly filtered gradient (outward from dense material);
//        where |g'| <= gate the colour stays unlit
//   Blend over:     C = a' c + (1 - a') C,  A = a' + (1 - a') A
//   Blend additive: C = C + a' c,           A = a' + (1 - a') A
//   MIP (vsi.mip.rule: max-α wins): a >= A_max: C = c_lit, A_max = a  (a the TF's intensity)
//   combined (vsi.combined.rule, OUR INTERPRETATION of the source's words, flagged in the run
//        record): a >= A_max: C = c_lit, A_max = a; else C = a' c_lit + (1 - a') C
// Output: RGB = C over the background (Blend: C + (1 - A) B; MIP and combined: C where A_max > 0,
// else B), alpha = A (Blend) or A_max. Blinn-Phong (vsi.light.*): c_lit = c (k_a + k_d max(n̂·l̂, 0))
// + k_s max(n̂·ĥ, 0)^e, l̂ towards the light, ĥ = normalise(l̂ + towards the eye); the light sits at
// eye + R_world_from_camera · p_cam · (box diagonal) (default p_cam = (1, 1, 1): right, down, forward).
//
// Parallel: TBB over image tiles; every pixel depends on its own ray only, so serial and parallel
// frames are bitwise equal.

#include <meltlab/core/image.h>
#include <meltlab/render/camera.h>
#include <meltlab/render/slicing/bloom.h>
#include <meltlab/render/slicing/gradient_volume.h>
#include <meltlab/render/slicing/mask_volume.h>
#include <meltlab/render/slicing/slice_geometry.h>
#include <meltlab/render/volume/transfer_function.h>
#include <meltlab/render/volume/volume.h>

#include <array>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace meltlab::render {

enum class SlicingMode { kBlend, kMip, kCombined };
/// vsi.blend.operator.
enum class BlendOperator { kOver, kAdditive };

struct BlinnPhong {
  double ambient = 0.2, diffuse = 0.7, specular = 0.3, exponent = 32;
  Eigen::Vector3d light_camera = Eigen::Vector3d::Ones();  ///< in box diagonals, camera frame
  double gate = 0;  ///< shade only where the decoded |g'| > gate (0: wherever a normal exists)
};

struct SlicingSettings {
  SlicingMode mode = SlicingMode::kBlend;
  double quality_class = 1.0;  ///< Δd = QC · h0
  SliceRange d_range = SliceRange::kTight;
  BlendOperator blend = BlendOperator::kOver;
  bool opacity_correction = true;
  bool lit_blend = false;  ///< vsi.shade.modes: light Blend samples too
  /// TF_1 .. TF_4 (a default TF has α = 0 everywhere).
  std::array<TransferFunction, 4> tfs;
  /// Empty: no mask (TF_1 everywhere).
  MaskVolume mask;
  /// vsi.data.norm_source: the value range mapped to [0, 1]; nullopt: the volume's scanned extrema.
  std::optional<std::pair<double, double>> value_range;
  GradientOptions gradient;
  BlinnPhong light;
  Eigen::Vector3d background = Eigen::Vector3d::Zero();
  BloomSettings post;  ///< colour adjustment always (identity by default), bloom if enabled
  bool parallel = true;
  int tile = 16;
  /// Empty-space skipping: samples in cells of skip_cell³ voxels where no TF in use can be visible
  /// (the cell's value range, padded by 1e-5 of its magnitude for float round-off, against
  /// visible_in) are not fetched. They would have α = 0 and be skipped anyway, so the image is the
  /// same bit for bit. Whole runs of such samples are jumped: with D the Chebyshev distance (in
  /// cells) from the sample's cell to the nearest live cell, the box of cells within D - 1 is empty,
  /// and the planes while the ray stays 0.01 voxel inside that box are counted as skipped without
  /// being visited (SlicingStats::visited counts the others).
  bool skip_empty = true;
  /// Edge of the empty-space cells in voxels: 2, 4 (default), 8 or 16 (the same image for any;
  /// smaller cells fit thin shells such as skin and bone tighter, at 8× the cells per halving).
  int skip_cell = 4;
  /// vsi.blend.early_termination: 0 (default, the source's back-to-front order): off. A value in
  /// (0, 1]: Blend with the over operator composites front to back (C += (1 - A) a' c, A += (1 -
  /// A) a': the same sum in another order, so pixels differ from the default by float round-off)
  /// and stops a ray once A >= the value (the rest could add at most (1 - A) to any channel of C).
  /// Ignored (logged as such) in the other modes and for the additive operator.
  double early_termination = 0;
  /// Sample positions. false (default): per ray, the first plane's index coordinates g_0 from
  /// t_k as below and the move per plane Δg, each rounded once to 32.32 fixed point, and sample j at
  /// g_0 + j Δg by integer arithmetic (fixed_position.h): no division, the same positions in every
  /// path, within (j + 1) 2⁻³³ voxel of the double arithmetic's, and the trilinear weights to 2⁻²⁴
  /// (see slicing_speed_test). true: each sample at o + t_k v with t_k from its plane's depth (one
  /// division per sample) and the weights of its float coordinates, as before issue 17's speed rounds.
  bool exact_positions = false;
  /// Live runs (with skip_empty, one ray at a time): from a sample in a live cell, the planes while
  /// the ray stays 0.01 voxel inside the cube of cells around it that are all live (the Chebyshev
  /// distance to the nearest empty cell minus one) are sampled without looking up their cells: the
  /// same samples, counts and image as testing each. false: every sample's cell is looked up (for
  /// tests and measurements). The packets' walk looks cells up every few planes either way.
  bool live_runs = true;
  /// Voxel bits (with skip_empty; issue 17's sixth speed round): inside live cells, a sample whose
  /// trilinear stencil (the voxels {i, i + 1} × {j, j + 1} × {k, k + 1} at its lower corner, clamped
  /// as the fetch clamps) holds no value that a TF in use can see (the stencil's range, padded as
  /// the cells' ranges, against visible_in) is not fetched: one bit per voxel (0.9 MB for a
  /// 256 × 256 × 113 volume, in bricks of 4³ voxels) looked up before the eight corners. Such a
  /// sample would have α = 0, so the image is the same bit for bit; it is counted as skipped. A cell
  /// none of whose voxels has its bit is empty (jumped). false: the bit is set for every voxel of a
  /// cell whose range a TF can see (every sample of a live cell is fetched: the image before that
  /// round, and its counts).
  bool skip_voxels = true;
  /// Packets (issue 17's speed rounds): true (default): neighbouring pixels of a tile (4 x 2 on
  /// eight lanes with AVX-512, 2 x 2 on four otherwise) advance plane by plane together, in two
  /// phases that take turns over chunks of planes: a walk over the planes that may hold a fetched
  /// sample of the packet's block of pixels (those where the box of the block's samples, from its
  /// corner rays, touches a live cell; a block is a tile, or fewer pixels in a coarse image) takes
  /// the lanes' positions and fetch bits (one gather) and queues the planes where some lane fetches;
  /// the fetch phase runs the trilinear gathers, the mask lookup, both TF kinds, the corrected α,
  /// the Blinn-Phong lighting (its specular power per lane) and the compositing on the lanes for
  /// those planes; a lane with nothing to do at a plane (outside its ray's planes, no fetch bit, cut
  /// away by the mask, terminated) is masked. Each lane fetches exactly its ray's samples with its
  /// ray's arithmetic (the scalar code's operations in its order): the image and the samples,
  /// skipped, classified and terminated counts are the scalar path's bit for bit
  /// (slicing_speed_test); visited and cell_tests count the packets' own work (lane positions, and
  /// planes bounded per block). Not with exact_positions. false: one ray at a time (the reference).
  bool simd = true;
  /// The corrected α 1 - (1 - α)^(Δ/h0), a power per sample of the linear TF and per ray and
  /// piece of the constant TF: false (default): for the constant TF slicing_corrected_alpha (issue
  /// 17's fourth speed round; eight lanes at a time in the packets, the same bits per lane as per
  /// ray; a short series for α <= 1/32; within (4 + e) 2^-53 of 1 - std::pow(1 - α, e)); for the
  /// linear TF, which is evaluated in float (the sample is a float; the thirteenth round),
  /// slicing_corrected_alpha_f (within 4 2^-24 of the exact value). true: std::pow (lane by lane
  /// in the packets; for the linear TF in double, rounded to float). Pixels differ from std::pow's
  /// by round-off only (one float ulp, plus 8 2^-24 with the linear TF; slicing_speed_test). The lit
  /// modes' specular term likewise: slicing_specular_power (on the lanes in the packets, issue 17's
  /// twelfth and fourteenth rounds), or std::pow with exact_pow.
  bool exact_pow = false;
};

/// Whether a mode needs the gradient volume.
bool slicing_needs_gradients(const SlicingSettings& s);

struct SlicingStats {
  std::int64_t rays = 0;        ///< pixels whose ray met the box
  std::int64_t samples = 0;     ///< plane samples taken (mask looked up)
  std::int64_t classified = 0;  ///< samples past the mask (TF evaluated)
  std::int64_t skipped = 0;     ///< samples in empty cells (not fetched)
  std::int64_t terminated = 0;  ///< rays stopped by early termination (their remaining samples not counted)
  std::int64_t visited =
      0;  ///< samples whose position was computed (the others jumped in empty runs; packets: lane positions)
  /// One ray at a time: visited samples whose empty-space cell was looked up (the others in live
  /// runs); packets: planes bounded per block of pixels.
  std::int64_t cell_tests = 0;
  int slices = 0;            ///< planes in the stack
  double slice_spacing = 0;  ///< Δd
  double render_ms = 0;      ///< sampling and compositing
  double post_ms = 0;        ///< colour adjustment and bloom
};

struct SlicingFrame {
  ImageF rgb;    ///< after the post chain
  ImageF raw;    ///< C over the background before the post chain
  ImageF alpha;  ///< A (Blend) or A_max (MIP, combined)
  SlicingStats stats;
};

/// Back-to-front compositing of one sample (exposed for the closed-form tests), in float: the TF's
/// values are floats (the linear kind is evaluated in float, the constant kind's rounded), and a
/// pixel's sum over its planes rounds once per plane, each rounding damped by the later planes'
/// transmittance (issue 17's thirteenth round; the packets composite eight lanes in one register).
struct SliceAccumulator {
  Eigen::Vector3f C = Eigen::Vector3f::Zero();
  float A = 0;  ///< Blend: accumulated opacity; MIP/combined: A_max
  void blend_over(const Eigen::Vector3f& c, float a) {
    C = a * c + (1 - a) * C;
    A = a + (1 - a) * A;
  }
  void blend_additive(const Eigen::Vector3f& c, float a) {
    C += a * c;
    A = a + (1 - a) * A;
  }
  void mip(const Eigen::Vector3f& c_lit, float a) {
    if (a >= A) C = c_lit, A = a;
  }
  void combined(const Eigen::Vector3f& c_lit, float a, float a_corrected) {
    if (a >= A)
      C = c_lit, A = a;
    else
      C = a_corrected * c_lit + (1 - a_corrected) * C;
  }
};

/// Checks the settings (InputError naming the parameter).
void check_slicing_settings(const Volume& volume, const SlicingSettings& settings);

/// The renderer's per-volume state: the value range, the gradient volume (when a mode needs it).
class SlicingRenderer {
 public:
  /// `gradients`: a prebuilt gradient volume (e.g. from cached_gradient_volume); built here when
  /// the mode needs one and none is given.
  SlicingRenderer(const Volume& volume, const SlicingSettings& settings,
                  std::optional<GradientVolume> gradients = std::nullopt);
  /// A frame seen by a pinhole camera (InputError for another camera, or an eye inside the box).
  SlicingFrame render(const Camera& camera) const;
  /// The same frame into `frame`, reusing its images' storage when they have the camera's size
  /// already (every pixel is written): a loop of frames then touches no new memory, whose page
  /// faults cost a fresh 1000 x 730 frame tens of milliseconds here. The same bits as render().
  void render_into(const Camera& camera, SlicingFrame& frame) const;
  const GradientVolume* gradients() const { return grad_ ? &*grad_ : nullptr; }
  std::pair<double, double> value_range() const { return {lo_, hi_}; }

 private:
  Volume volume_;
  SlicingSettings s_;
  std::optional<GradientVolume> grad_;
  double lo_ = 0, hi_ = 1;
  std::array<bool, 4> tf_used_{true, false, false, false};  ///< TFs the mask uses (TF 1 without a mask)
  int cell_shift_ = 3;                                      ///< log2 of the empty-space cell edge (voxels)
  std::array<int, 3> cells_{0, 0, 0};                       ///< empty-space cells of skip_cell³ voxels
  std::vector<std::uint8_t> live_;                          ///< 1 where some sample is fetched (fetch_bits_)
  /// Chebyshev distance (in cells, capped at 255) from each cell to the nearest live cell (0: live).
  std::vector<std::uint8_t> dist_;
  /// For a live cell, the radius (in cells) of the cube around it whose cells are all live: the
  /// Chebyshev distance to the nearest empty cell minus one (0 for empty cells).
  std::vector<std::uint8_t> live_reach_;
  /// Prefix sums of live_ ((cells + 1) per axis, x fastest): the live cells of any box by eight
  /// lookups (the packets' planes per tile).
  std::vector<std::int32_t> live_sums_;
  /// The fetch bits (with skip_empty): one per voxel, set where a sample whose stencil's lower
  /// corner is that voxel is fetched — with skip_voxels where a TF in use may see a value of the
  /// stencil, else wherever the voxel's cell may be seen. In bricks of 4³ voxels, one 64-bit word
  /// each (bricks_ per axis, x fastest; bit (i & 3) + 4 (j & 3) + 16 (k & 3)): a ray's steps stay in
  /// one word for a few planes, and a zero word tells that the brick has nothing to fetch. A cell is
  /// live (live_) where some voxel of it has its bit.
  std::vector<std::uint64_t> fetch_bits_;
  std::array<int, 3> bricks_{0, 0, 0};
  /// The gradient's three encoded channels of each voxel (x fastest) as e_x | e_y << 8 | e_z << 16:
  /// one 32-bit gather per corner in the packets' lighting (simd and a lit mode).
  std::vector<std::int32_t> grad_words_;
};

/// x^y for x, y >= 0 finite as the renderer computes its per-sample powers (SlicingSettings::exact_pow
/// false): within 1e-14 of std::pow relative (subnormal results within 1e-300 absolute).
double slicing_pow(double x, double y);

/// The specular power x^y (x in [0, 1], y >= 0 finite) as the renderer computes it (SlicingSettings::exact_pow
/// false), in double before it is rounded to float: for an integer y in [1, 1024] by binary exponentiation
/// (within 2 y 2^-53 of std::pow relative while normal), else slicing_pow.
double slicing_specular_power(double x, double y);
/// The same on the packets' lanes: out[i] has the bits of slicing_specular_power(x[i], y).
void slicing_specular_power_lanes(std::span<const double> x, double y, std::span<double> out);

/// The opacity correction 1 - (1 - a)^e as the renderer computes it (SlicingSettings::exact_pow false):
/// short series for ln(1 - a) and e^t - 1 where a <= 1/32 and |e ln(1 - a)| <= 1/16, else 1 -
/// slicing_pow(1 - a, e); within (4 + e) 2^-53 of 1 - std::pow(1 - a, e) absolute, for a in [0, 1], e >= 0.
double slicing_corrected_alpha(double a, double e);
/// The same on the packets' lanes (packet::kLanes at a time: eight with AVX-512, else four; the last
/// packet padded): out[i] has the bits of
/// slicing_corrected_alpha(a[i], e[i]) whatever branch the other lanes of its packet take.
void slicing_corrected_alpha_lanes(std::span<const double> a, std::span<const double> e, std::span<double> out);

/// The linear TF's opacity correction as the renderer computes it per sample, in float (issue 17's
/// thirteenth round; SlicingSettings::exact_pow false): the short series of slicing_corrected_alpha cut
/// to float's precision where a <= 1/32 and |e ln(1 - a)| <= 1/16 (within 8 2^-24 of the exact value
/// relative), else slicing_corrected_alpha(a, e) rounded to float.
float slicing_corrected_alpha_f(float a, float e);
/// The same on the packets' lanes: out[i] has the bits of slicing_corrected_alpha_f(a[i], e[i]).
void slicing_corrected_alpha_f_lanes(std::span<const float> a, std::span<const float> e, std::span<float> out);
/// A TF of the piecewise-linear kind at the normalised sample value v as the renderer evaluates it:
/// in float (the control points rounded to float; TfCurve::at's form), within a few 2^-24 of
/// TransferFunction::evaluate(v) scaled by the curves' slopes (tested). Throws std::invalid_argument
/// for the constant kind (evaluated as TransferFunction does, in double).
TfValue slicing_linear_tf_value(const TransferFunction& tf, float v);

/// One frame (builds a SlicingRenderer).
SlicingFrame render_slicing(const Volume& volume, const Camera& camera, const SlicingSettings& settings);

std::string slicing_mode_name(SlicingMode m);

/// Every vsi.* choice of a render with its value (name/value text pairs, for the run record).
std::vector<std::pair<std::string, std::string>> describe_vsi(const SlicingSettings& s, const Volume& volume,
                                                              const Camera& camera);

}  // namespace meltlab::render
