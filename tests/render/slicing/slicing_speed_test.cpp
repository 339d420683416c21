// The slicing renderer's speed paths (render/slicing/slicing_renderer.h) against its plain path:
// jumping runs of empty planes changes no pixel for any cell size, mode, mask or camera; early ray
// termination is off by default, ignored where it does not apply, equal to back to front up to
// float round-off when it cannot stop early, and within its bound when it does; live runs change
// no pixel or count; incremental sample positions equal the exact ones up to float round-off; a
// linear TF's shared control points give the bits of per-channel evaluation.

#include <meltlab/core/error.h>
#include <meltlab/render/slicing/slicing_renderer.h>
#include <meltlab/render/slicing/test_fields.h>
#include <meltlab/render/volume/generate.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

namespace meltlab::render {
namespace {

/// Renders `cam` with settings `s`, reusing the gradient volume `other` built (if it built one):
/// the comparisons below change one setting between two renderers of the same volume.
SlicingFrame render_reusing_gradients(const Volume& v, const SlicingSettings& s, const SlicingRenderer& other,
                                      const Camera& cam) {
  return SlicingRenderer(v, s, other.gradients() ? std::optional<GradientVolume>(*other.gradients()) : std::nullopt)
      .render(cam);
}

/// Frames of `cam` with the switch `flag` of `s` off, then on (the second renderer reuses the
/// gradients of the first): a speed path against the path without it.
std::pair<SlicingFrame, SlicingFrame> off_then_on(const Volume& v, SlicingSettings s, bool SlicingSettings::*flag,
                                                  const Camera& cam) {
  s.*flag = false;
  const SlicingRenderer off(v, s);
  SlicingFrame without = off.render(cam);
  s.*flag = true;
  return {std::move(without), render_reusing_gradients(v, s, off, cam)};
}

Camera camera_30deg(int w, int h, const Box3& box, const Eigen::Vector3d& dir) {
  const double fy = 0.5 * h / std::tan(15.0 * M_PI / 180.0);
  Eigen::Vector3d up(0, 0, 1);
  if (std::abs(dir.normalized().z()) > 0.99) up = Eigen::Vector3d(0, 1, 0);
  return Pinhole::look_at(w, h, fy, box.centre() + dir, box.centre(), up);
}

/// A small CT phantom (nested shells with noise, spacing 1 : 1 : 2) normalised as a scene does.
const Volume& phantom() {
  static const Volume v = [] {
    VolumeGenerateOptions g;
    g.kind = VolumeKind::kCtPhantom;
    g.nx = 48, g.ny = 44, g.nz = 21;
    return generate_volume(g);
  }();
  return v;
}

/// Skin (air–fat transition and fat) faint, bone strong; water and muscle invisible: thin live shells.
TransferFunction skin_bone() {
  std::vector<TfRange> r(2);
  r[0] = {0.23, 0.455, false, true, Eigen::Vector3d(230, 170, 140), 0.08};
  r[1] = {0.75, 1.0, false, true, Eigen::Vector3d(255, 250, 240), 0.6};
  return TransferFunction(r, "skin_bone");
}

TransferFunction highlight() {
  std::array<TfCurve, 4> c;
  c[0].points = {{0.0, 1.0}};
  c[1].points = {{0.0, 0.3}, {1.0, 0.6}};
  c[2].points = {{0.0, 0.1}};
  c[3].points = {{0.3, 0.0}, {0.5, 0.4}, {1.0, 0.7}};
  return TransferFunction::piecewise_linear(c, "highlight");
}

double max_abs_diff(const ImageF& a, const ImageF& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(double(a.values()[i]) - double(b.values()[i])));
  return m;
}

/// The cameras of the tests: oblique, axis-aligned (ray moves of 0 on two axes), close (rays leave
/// through the volume's sides, where clamped indices meet the jump's open box sides).
std::vector<Camera> cameras(const Box3& box) {
  const double d = box.diagonal();
  return {camera_30deg(44, 32, box, Eigen::Vector3d(0.9, -1.3, 0.7).normalized() * 1.6 * d),
          camera_30deg(40, 30, box, Eigen::Vector3d(0, 0, 1) * 1.8 * d),
          camera_30deg(36, 28, box, Eigen::Vector3d(-0.5, 0.4, -0.3).normalized() * 0.75 * d)};
}

/// The mask of the identity tests: the top cut away, a sphere with the second TF.
MaskVolume test_mask(const Volume& v) {
  MaskVolume mask({12, 11, 9}, v.domain(), 1);
  MaskEdit cut;
  cut.centre = Eigen::Vector3d(0.5, 0.5, 0.9), cut.half_size = Eigen::Vector3d(0.6, 0.6, 0.2), cut.index = 0;
  mask.apply(cut);
  MaskEdit hl;
  hl.shape = MaskShape::kSphere, hl.centre = Eigen::Vector3d(0.4, 0.45, 0.5), hl.half_size.setConstant(0.2);
  hl.index = 2;
  mask.apply(hl);
  return mask;
}

/// Variant 0 Blend over, 1 additive, 2 MIP, 3 combined, 4 masked lit Blend, 5 front to back (0.99).
SlicingSettings variant_settings(const Volume& v, int variant) {
  SlicingSettings s;
  s.tfs[0] = skin_bone();
  s.tfs[1] = highlight();
  s.quality_class = 0.7;
  s.mode = variant == 2 ? SlicingMode::kMip : variant == 3 ? SlicingMode::kCombined : SlicingMode::kBlend;
  s.blend = variant == 1 ? BlendOperator::kAdditive : BlendOperator::kOver;
  if (variant == 4) s.mask = test_mask(v), s.lit_blend = true;
  if (variant == 5) s.early_termination = 0.99;
  return s;
}

TEST(SlicingSpeed, JumpingEmptyRunsChangesNoPixelForAnyCellSizeModeOrMask) {
  const Volume& v = phantom();
  for (const Camera& cam : cameras(v.domain()))
    for (int variant = 0; variant < 5; ++variant) {
      SlicingSettings s = variant_settings(v, variant);
      s.skip_empty = false;
      const SlicingRenderer plain_renderer(v, s);
      const SlicingFrame plain = plain_renderer.render(cam);
      EXPECT_EQ(plain.stats.visited, plain.stats.samples);
      ASSERT_GT(plain.stats.classified, 0);
      for (int cell : {2, 4, 8, 16}) {
        s.skip_empty = true;
        s.skip_cell = cell;
        const SlicingFrame f = render_reusing_gradients(v, s, plain_renderer, cam);
        const std::string what = "variant " + std::to_string(variant) + ", cell " + std::to_string(cell);
        EXPECT_EQ(f.raw, plain.raw) << what;
        EXPECT_EQ(f.alpha, plain.alpha) << what;
        EXPECT_EQ(f.stats.samples, plain.stats.samples) << what;  // jumped planes are still counted
        EXPECT_LE(f.stats.visited, f.stats.samples) << what;
        // The test must exercise the jumps, not only the per-sample check: cells of 2 to 8 voxels
        // leave empty runs on every ray set here (16 makes 3 x 3 x 2 cells on this volume, all live).
        if (cell <= 8) {
          EXPECT_LT(f.stats.visited, f.stats.samples) << what;
        }
      }
    }
}

TEST(SlicingSpeed, EarlyTerminationIsOffByDefaultAndIgnoredOutsideBlendOver) {
  const Volume& v = phantom();
  const Camera cam = cameras(v.domain())[0];
  SlicingSettings s;
  EXPECT_EQ(s.early_termination, 0.0);
  s.tfs[0] = skin_bone();
  for (int variant = 0; variant < 3; ++variant) {
    s.mode = variant == 1 ? SlicingMode::kMip : variant == 2 ? SlicingMode::kCombined : SlicingMode::kBlend;
    s.blend = variant == 0 ? BlendOperator::kAdditive : BlendOperator::kOver;
    s.early_termination = 0;
    const SlicingFrame a = render_slicing(v, cam, s);
    s.early_termination = 0.5;
    const SlicingFrame b = render_slicing(v, cam, s);
    EXPECT_EQ(a.raw, b.raw) << variant;
    EXPECT_EQ(b.stats.terminated, 0) << variant;
  }
}

TEST(SlicingSpeed, FrontToBackEqualsBackToFrontUpToRoundOffAndStopsWithinItsBound) {
  const Volume& v = phantom();
  for (const Camera& cam : cameras(v.domain())) {
    SlicingSettings s;
    s.tfs[0] = skin_bone();
    s.quality_class = 0.5;
    s.background = Eigen::Vector3d(0.2, 0.4, 0.9);
    const SlicingFrame back_to_front = render_slicing(v, cam, s);
    // Threshold 1: a ray stops only where A is 1 in double precision, so nothing behind can count;
    // the two orders differ by double round-off, a float ulp at most after the cast (values <= 1
    // carry ulps <= 6e-8; 1e-6 leaves room for a few).
    s.early_termination = 1.0;
    const SlicingFrame whole = render_slicing(v, cam, s);
    EXPECT_LE(max_abs_diff(whole.raw, back_to_front.raw), 1e-6);
    EXPECT_LE(max_abs_diff(whole.alpha, back_to_front.alpha), 1e-6);
    // Threshold 0.99: what is left behind the stop is (1 - A) <= 0.01 times a mixture of colours and
    // the background, all in [0, 1]; so every channel moves by at most 0.01 (+ the round-off above).
    s.early_termination = 0.99;
    const SlicingFrame stopped = render_slicing(v, cam, s);
    EXPECT_LE(max_abs_diff(stopped.raw, back_to_front.raw), 0.01 + 1e-6);
    EXPECT_LE(max_abs_diff(stopped.alpha, back_to_front.alpha), 0.01 + 1e-6);
    EXPECT_GT(stopped.stats.terminated, 0);
    EXPECT_LT(stopped.stats.samples, back_to_front.stats.samples);
    for (std::size_t i = 0; i < stopped.alpha.size(); ++i)
      if (back_to_front.alpha.values()[i] >= 0.995f) {
        EXPECT_GE(stopped.alpha.values()[i], 0.99f - 1e-6f);
      }
  }
}

TEST(SlicingSpeed, LiveRunsChangeNoPixelOrCountAndSaveCellLookups) {
  // One ray at a time, live runs replace the cell test of every sample in a live cube: the same
  // samples, visits and counts with fewer lookups. The packets' walk looks cells up every few
  // planes whatever they hold, so the setting changes nothing there.
  const Volume& v = phantom();
  for (const Camera& cam : cameras(v.domain()))
    for (int variant = 0; variant < 6; ++variant)
      for (int cell : {2, 4, 8})
        for (const bool simd : {false, true}) {
          SlicingSettings s = variant_settings(v, variant);
          s.skip_cell = cell;
          s.simd = simd;
          const auto [tested, runs] = off_then_on(v, s, &SlicingSettings::live_runs, cam);
          const std::string what =
              "variant " + std::to_string(variant) + ", cell " + std::to_string(cell) + (simd ? ", packets" : "");
          EXPECT_EQ(runs.raw, tested.raw) << what;
          EXPECT_EQ(runs.alpha, tested.alpha) << what;
          EXPECT_EQ(runs.stats.samples, tested.stats.samples) << what;
          EXPECT_EQ(runs.stats.skipped, tested.stats.skipped) << what;
          EXPECT_EQ(runs.stats.classified, tested.stats.classified) << what;
          EXPECT_EQ(runs.stats.terminated, tested.stats.terminated) << what;
          if (!simd) {
            EXPECT_EQ(runs.stats.visited, tested.stats.visited) << what;
            EXPECT_EQ(tested.stats.cell_tests, tested.stats.visited) << what;
            // At QC 0.7 several planes cross each live cell, so runs must save lookups in every case.
            EXPECT_LT(runs.stats.cell_tests, runs.stats.visited) << what;
          } else {  // the packets' walk has no live runs
            EXPECT_EQ(runs.stats.cell_tests, tested.stats.cell_tests) << what;
            EXPECT_EQ(runs.stats.visited, tested.stats.visited) << what;
          }
        }
}

TEST(SlicingSpeed, VoxelBitsChangeNoPixelAndFetchFewerSamples) {
  // The voxel bits skip samples whose trilinear stencil no TF in use can see. A bit that forgot the
  // stencil's upper neighbours, was indexed with another axis order or left out a TF the mask uses
  // would drop visible samples, and the pixels would change; the counts show that it skips some.
  const Volume& v = phantom();
  for (const Camera& cam : cameras(v.domain()))
    for (int variant = 0; variant < 6; ++variant)
      for (const bool simd : {true, false}) {
        SlicingSettings s = variant_settings(v, variant);
        s.simd = simd;
        const auto [plain, f] = off_then_on(v, s, &SlicingSettings::skip_voxels, cam);
        const std::string what = "variant " + std::to_string(variant) + (simd ? ", packets" : ", rays");
        EXPECT_EQ(f.raw, plain.raw) << what;
        EXPECT_EQ(f.alpha, plain.alpha) << what;
        EXPECT_EQ(f.stats.samples, plain.stats.samples) << what;
        EXPECT_EQ(f.stats.terminated, plain.stats.terminated) << what;
        EXPECT_LT(f.stats.samples - f.stats.skipped, plain.stats.samples - plain.stats.skipped) << what;
        EXPECT_LE(f.stats.classified, plain.stats.classified) << what;
      }
  // A volume whose values every TF sees has every bit set: the same fetches as without them.
  Volume flat = Volume::allocate(6, 5, 4, SampleType::kFloat32);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 6; ++i) flat.set_value(i, j, k, 0.8 + 0.01 * ((i + 2 * j + 3 * k) % 7));
  SlicingSettings s;
  s.tfs[0] = skin_bone();
  s.value_range = std::make_pair(0.0, 1.0);
  const Camera cam = cameras(flat.domain())[0];
  const SlicingFrame with = render_slicing(flat, cam, s);
  s.skip_voxels = false;
  const SlicingFrame without = render_slicing(flat, cam, s);
  EXPECT_EQ(with.raw, without.raw);
  EXPECT_EQ(with.stats.skipped, without.stats.skipped);
  EXPECT_GT(with.stats.samples - with.stats.skipped, 0);
}

TEST(SlicingSpeed, IncrementalPositionsEqualExactOnesUpToFloatRoundOff) {
  // g_0 + j dg (one rounding per axis) and (o + t_k v - origin) / spacing differ by ~1e-13 voxel
  // in double (|g| < 64 here); after the cast to float the two are equal or one float ulp apart
  // (<= 2^-18 ~ 3.8e-6 voxel for |g| < 64), which moves a trilinear value (normalised, neighbours
  // differ by <= 1) by <= 3.8e-6 and a linear TF (slopes <= 2 here) by <= 7.6e-6 per sample. A
  // constant TF's range edge could flip a sample, but that needs the value within 3.8e-6 of the
  // edge as well (none here: the test would show it). kTol: the per-sample bound, 1e-5.
  constexpr double kTol = 1e-5;
  const Volume& v = phantom();
  for (const Camera& cam : cameras(v.domain()))
    for (int variant = 0; variant < 6; ++variant) {
      SlicingSettings s = variant_settings(v, variant);
      s.exact_positions = true;
      const SlicingRenderer exact_renderer(v, s);
      const SlicingFrame exact = exact_renderer.render(cam);
      s.exact_positions = false;
      const SlicingFrame fast = render_reusing_gradients(v, s, exact_renderer, cam);
      const std::string what = "variant " + std::to_string(variant);
      EXPECT_LE(max_abs_diff(fast.raw, exact.raw), kTol) << what;
      EXPECT_LE(max_abs_diff(fast.alpha, exact.alpha), kTol) << what;
      EXPECT_EQ(fast.stats.samples, exact.stats.samples) << what;
      EXPECT_GT(exact.stats.classified, 0) << what;
    }
  EXPECT_FALSE(SlicingSettings{}.exact_positions);  // the default is the incremental form
}

TEST(SlicingSpeed, CurvesSharingControlPointsGiveTheBitsOfPerChannelEvaluation) {
  // A scene's `points` rows give four curves with the same x: the renderer then finds the segment
  // once per sample. The same TF with a redundant point (x = 2, the end value) on the red curve
  // only is evaluated per channel (TfCurve::at's way); on [0, 1] both are the same function with
  // the same segments and t, so every pixel must agree bit for bit.
  const double rows[5][5] = {{0.2, 0.9, 0.5, 0.1, 0},
                             {0.35, 0.8, 0.6, 0.2, 0.3},
                             {0.5, 0.3, 0.9, 0.4, 0.05},
                             {0.8, 0.6, 0.6, 0.9, 0.5},
                             {1, 1, 0.2, 0.5, 0.7}};
  std::array<TfCurve, 4> shared;
  for (const auto& r : rows)
    for (int c = 0; c < 4; ++c) shared[std::size_t(c)].points.emplace_back(r[0], r[c + 1]);
  std::array<TfCurve, 4> per_channel = shared;
  per_channel[0].points.emplace_back(2.0, rows[4][1]);
  const Volume& v = phantom();
  for (const Camera& cam : cameras(v.domain()))
    for (int variant : {0, 3}) {  // Blend, combined (lit)
      SlicingSettings s = variant_settings(v, variant);
      s.tfs[0] = TransferFunction::piecewise_linear(shared, "shared");
      const SlicingRenderer a_renderer(v, s);
      const SlicingFrame a = a_renderer.render(cam);
      s.tfs[0] = TransferFunction::piecewise_linear(per_channel, "per_channel");
      const SlicingFrame b = render_reusing_gradients(v, s, a_renderer, cam);
      EXPECT_EQ(a.raw, b.raw) << variant;
      EXPECT_EQ(a.alpha, b.alpha) << variant;
      EXPECT_GT(a.stats.classified, 0) << variant;
      EXPECT_GT(max_abs_diff(a.raw, ImageF(a.raw.width(), a.raw.height(), 3)), 0.05) << variant;  // not blank
    }
}

/// A linear TF whose four curves share `n` control points spread over [0.3, 1] (α 0 below, so the
/// air is empty space; α > 0 at every third point, colours varying): n - 1 segments (more than
/// eight: the packets read the segment tables lane by lane; up to eight: by one permute).
TransferFunction shared_points(int n) {
  std::array<TfCurve, 4> c;
  for (int i = 0; i < n; ++i) {
    const double x = 0.3 + 0.7 * double(i) / (n - 1);
    c[0].points.emplace_back(x, 0.5 + 0.5 * std::sin(3.0 * i));
    c[1].points.emplace_back(x, double(i % 3) / 2);
    c[2].points.emplace_back(x, 1.0 - x);
    c[3].points.emplace_back(x, i % 3 == 1 ? 0.1 + 0.4 * x : 0.0);
  }
  return TransferFunction::piecewise_linear(c, "shared_" + std::to_string(n));
}

/// test_mask with regions of index 3 and 4 added: every index 0-4 is used.
MaskVolume all_index_mask(const Volume& v) {
  MaskVolume mask = test_mask(v);
  MaskEdit e;
  e.centre = Eigen::Vector3d(0.75, 0.3, 0.4), e.half_size = Eigen::Vector3d(0.2, 0.25, 0.3), e.index = 3;
  mask.apply(e);
  e.shape = MaskShape::kEllipsoid, e.centre = Eigen::Vector3d(0.3, 0.75, 0.35);
  e.half_size = Eigen::Vector3d(0.25, 0.2, 0.3), e.rotate_deg = Eigen::Vector3d(10, 20, 30), e.index = 4;
  mask.apply(e);
  return mask;
}

TEST(SlicingSpeed, PacketsGiveTheScalarPathsPixelsAndFetchesBitForBit) {
  // The SIMD path (SlicingSettings::simd) runs each lane through its ray's scalar arithmetic (the
  // same fma positions, float trilinear order, the TF's range tests in double, the linear TF, lighting and compositing
  // in float; -ffp-contract=off keeps both free of fused operations) and fetches exactly the samples in live cells that
  // the ray fetches, so pixels and the sample, skip, classification and termination counts must be equal, not close.
  // Variants 0-5 as above, 6: the linear TF unmasked (classified lane by lane), 7: a mask with two constant TFs unlit
  // (the eight-lane range tests under a mask), 8: opacity correction off and additive with a background, 9 and 10:
  // Blend and combined on an 8-bit copy of the volume, 11 and 12: a mask using every index with TF 1 constant, TF 2
  // linear with curves of their own points, TF 3 linear with 11 shared segments, TF 4 with 5 (the lanes' TF, mask and
  // light together) in Blend and combined, 13: MIP with the 11-segment TF and a gate and exponent of its own (unlit
  // lanes among lit ones), 14: lit Blend with the 5-segment TF, 15: variant 12 with std::pow (exact_pow, lane by lane),
  // 16 and 17: Blend and combined on a two-valued copy of the volume (0 and 1: trilinear samples in uniform regions are
  // exactly 0 or 1) with constant-TF ranges [0.5, 1) and [1, 1] (the lanes' float range tests at a bound that most
  // samples of the object hit exactly, from both sides), 18-20: the two-valued copy with a linear TF from 0 to 1 (its
  // end rows at equality) in Blend, combined, and Blend with a colour of -0; tiles of 16, 5 and 10 pixels (packets cut
  // at the tile's edge; 10: fifteen 4 x 2 blocks, so the packets' pairs cross block rows and one packet runs alone) and
  // no skipping.
  const Volume& v = phantom();
  TransferFunction bone_only;
  {
    std::vector<TfRange> r(1);
    r[0] = {0.5, 0.9, true, false, Eigen::Vector3d(200, 220, 255), 0.3};
    bone_only = TransferFunction(r, "bone_only");
  }
  // An 8-bit copy (value scale 1/255): the packets' per-lane fetch of non-float samples.
  Volume bytes = Volume::allocate(v.nx(), v.ny(), v.nz(), SampleType::kUint8);
  bytes.place_like(v);
  bytes.set_value_scale(1.0 / 255);
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) bytes.set_value(i, j, k, v.value(i, j, k));
  // The two-valued copy: 1 where the phantom is above the middle of its range, else 0.
  Volume binary = Volume::allocate(v.nx(), v.ny(), v.nz(), SampleType::kFloat32);
  binary.place_like(v);
  const auto vr = v.value_range();
  const double middle = 0.5 * (double(vr[0]) + double(vr[1]));
  std::int64_t ones = 0;
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) {
        const bool one = double(v.value(i, j, k)) > middle;
        binary.set_value(i, j, k, one ? 1.0 : 0.0);
        ones += one ? 1 : 0;
      }
  ASSERT_GT(ones, 0);
  // (0.01, 0.5) one colour, [0.5, 1) another, [1, 1] a third (0 in none: the outside is empty).
  TransferFunction edges;
  {
    std::vector<TfRange> r(3);
    r[0] = {0.01, 0.5, false, false, Eigen::Vector3d(255, 60, 20), 0.25};
    r[1] = {0.5, 1.0, true, false, Eigen::Vector3d(30, 255, 90), 0.4};
    r[2] = {1.0, 1.0, true, true, Eigen::Vector3d(40, 70, 255), 0.6};
    edges = TransferFunction(r, "edges");
  }
  // A linear TF from 0 to 1 (shared points; α > 0 at both ends): on the two-valued copy every
  // sample is at the first point (0) or the last (1), where both paths take the end values; the
  // same with a colour of -0 at the first point (kept as -0 by both).
  TransferFunction ends_tf, ends_tf_neg_zero;
  {
    const double rows[3][5] = {{0.0, 0.9, 0.2, 0.1, 0.15}, {0.4, 0.3, 0.8, 0.2, 0.5}, {1.0, 0.2, 0.3, 0.9, 0.6}};
    std::array<TfCurve, 4> c;
    for (const auto& r : rows)
      for (int ch = 0; ch < 4; ++ch) c[std::size_t(ch)].points.emplace_back(r[0], r[ch + 1]);
    ends_tf = TransferFunction::piecewise_linear(c, "ends");
    c[2].points[0].y() = -0.0;
    ends_tf_neg_zero = TransferFunction::piecewise_linear(c, "ends_neg_zero");
  }
  int compared = 0;
  for (const Camera& cam : cameras(v.domain()))
    for (int variant = 0; variant < 21; ++variant)
      for (int tile : {16, 5, 10})
        for (bool skip : {true, false}) {
          if (!skip && tile != 16) continue;
          SlicingSettings s = variant_settings(v, variant < 6 ? variant : variant == 10 ? 3 : 0);
          if (variant == 6) s.tfs[0] = highlight();
          if (variant == 7) s.mask = test_mask(v), s.tfs[1] = bone_only;
          if (variant == 8) {
            s.opacity_correction = false, s.blend = BlendOperator::kAdditive;
            s.background = Eigen::Vector3d(0.2, 0.4, 0.9);
          }
          if (variant == 11 || variant == 12 || variant == 15) {
            s.mask = all_index_mask(v);
            s.tfs[2] = shared_points(12), s.tfs[3] = shared_points(6);
            s.mode = variant == 11 ? SlicingMode::kBlend : SlicingMode::kCombined;
            s.exact_pow = variant == 15;
          }
          if (variant == 13) {
            s.mode = SlicingMode::kMip, s.tfs[0] = shared_points(12);
            s.light.gate = 0.3, s.light.exponent = 7.5, s.light.light_camera = Eigen::Vector3d(0.4, -0.4, 0);
          }
          if (variant == 14) s.lit_blend = true, s.tfs[0] = shared_points(6);
          if (variant == 16 || variant == 17) {
            s.tfs[0] = edges, s.value_range = std::make_pair(0.0, 1.0);  // fn = f: the bounds are the samples'
            s.mode = variant == 16 ? SlicingMode::kBlend : SlicingMode::kCombined;
          }
          if (variant >= 18) {  // the linear TF's end rows at v equal to the first and the last point
            s.tfs[0] = variant == 20 ? ends_tf_neg_zero : ends_tf, s.value_range = std::make_pair(0.0, 1.0);
            s.mode = variant == 19 ? SlicingMode::kCombined : SlicingMode::kBlend;
          }
          s.tile = tile;
          s.skip_empty = skip;
          s.simd = false;
          const Volume& vol = variant >= 16 ? binary : variant >= 9 ? bytes : v;
          const SlicingRenderer scalar_renderer(vol, s);
          const SlicingFrame scalar = scalar_renderer.render(cam);
          s.simd = true;
          const SlicingFrame packets = render_reusing_gradients(vol, s, scalar_renderer, cam);
          const std::string what = "variant " + std::to_string(variant) + ", tile " + std::to_string(tile) + ", skip " +
                                   std::to_string(skip);
          EXPECT_EQ(packets.raw, scalar.raw) << what << ", max diff " << max_abs_diff(packets.raw, scalar.raw);
          EXPECT_EQ(packets.alpha, scalar.alpha) << what;
          EXPECT_EQ(packets.stats.rays, scalar.stats.rays) << what;
          EXPECT_EQ(packets.stats.samples, scalar.stats.samples) << what;
          EXPECT_EQ(packets.stats.skipped, scalar.stats.skipped) << what;  // the same samples fetched
          EXPECT_EQ(packets.stats.classified, scalar.stats.classified) << what;
          // Positions and cell lookups are the packet's own (the planes per block of pixels, not
          // per ray).
          EXPECT_LE(packets.stats.visited, packets.stats.samples) << what;
          if (skip) {
            if (variant < 18) {  // (18-20 see every value: no empty space)
              EXPECT_LT(packets.stats.visited, packets.stats.samples) << what;  // the packets skip planes
            }
            EXPECT_GT(packets.stats.cell_tests, 0) << what;  // planes bounded per block
          } else {
            EXPECT_EQ(packets.stats.visited, scalar.stats.visited) << what;
            EXPECT_EQ(packets.stats.cell_tests, 0) << what;
          }
          EXPECT_EQ(packets.stats.terminated, scalar.stats.terminated) << what;
          EXPECT_GT(scalar.stats.classified, 0) << what;
          if (variant == 5) {
            EXPECT_GT(scalar.stats.terminated, 0) << what;
          }
          ++compared;
        }
  EXPECT_EQ(compared, 3 * 21 * 4);
  const auto h = all_index_mask(v).histogram();
  for (int i = 0; i < 5; ++i) EXPECT_GT(h[std::size_t(i)], 0) << "mask index " << i;
  EXPECT_TRUE(SlicingSettings{}.simd);
  // A distorted pinhole: its rays are no affine family, so the packets walk every plane of a
  // tile (no planes bounded per block) while skipping by the voxels' fetch bits; Blend, the
  // linear TF and front to back with early termination.
  Pinhole distorted = std::get<Pinhole>(cameras(v.domain())[0]);
  distorted.distortion = {-0.12, 0.03, 0.002, -0.001, 0};
  ASSERT_TRUE(distorted.distorted());
  for (int variant : {0, 5, 6}) {
    SlicingSettings s = variant_settings(v, variant == 6 ? 0 : variant);
    if (variant == 6) s.tfs[0] = highlight();
    const auto [scalar, packets] = off_then_on(v, s, &SlicingSettings::simd, distorted);
    const std::string what = "distorted, variant " + std::to_string(variant);
    EXPECT_EQ(packets.raw, scalar.raw) << what << ", max diff " << max_abs_diff(packets.raw, scalar.raw);
    EXPECT_EQ(packets.alpha, scalar.alpha) << what;
    EXPECT_EQ(packets.stats.skipped, scalar.stats.skipped) << what;
    EXPECT_EQ(packets.stats.classified, scalar.stats.classified) << what;
    EXPECT_EQ(packets.stats.terminated, scalar.stats.terminated) << what;
    EXPECT_EQ(packets.stats.cell_tests, 0) << what;  // no planes bounded per block
    EXPECT_GT(scalar.stats.classified, 0) << what;
  }
}

TEST(SlicingSpeed, SlicingPowIsStdPowUpToRoundOff) {
  // slicing_pow (lane_math.h; the linear TF's corrected α): ln x to a few ulps, then e^t, t = y ln x: the absolute
  // error of t (a few ulps of |t|) becomes a relative error of e^t, so the bound grows with |t|: |pow - std::pow| <=
  // (16 + 4 |t|) eps |std::pow| (eps = 2^-53; 16 eps for ln m's series and e^r's polynomial and the scalings, 4 |t| eps
  // for t's rounding), while the result is normal.
  constexpr double kEps = 0x1p-53;
  int checked = 0;
  double worst = 0;  // in units of the bound
  for (double y : {0.25, 0.5, 1.0, 1.0001, 1.37, 2.0, 3.7, 7.5, 32.0, 128.0, 1000.0})
    for (int i = 1; i <= 4000; ++i) {
      // x from 1e-12 to 1 (log-spaced), and 1 - a for small a (the opacity correction's range)
      const double x =
          i <= 2000 ? std::pow(10.0, -12.0 * (2000 - i) / 1999) : 1.0 - std::pow(10.0, -8.0 * (i - 2000) / 2000);
      const double ref = std::pow(x, y);
      if (!(ref > 0x1p-1000)) continue;
      const double t = std::abs(y * std::log(x));
      const double bound = (16 + 4 * t) * kEps * ref;
      const double err = std::abs(slicing_pow(x, y) - ref);
      worst = std::max(worst, err / bound);
      ASSERT_LE(err, bound) << "x " << x << ", y " << y;
      ++checked;
    }
  EXPECT_GT(checked, 30000);
  // The opacity correction 1 - (1 - α)^e at the renderer's α (TF values) and exponents (Δ / h0 at
  // QC 0.5-4 and oblique rays): within 4 eps absolute, i.e. α' keeps about its last bit.
  for (double e : {0.5, 0.93, 1.0, 1.07, 1.5, 2.0, 4.0})
    for (int i = 1; i <= 1000; ++i) {
      const double a = i / 1000.0;
      ASSERT_LE(std::abs((1.0 - slicing_pow(1.0 - a, e)) - (1.0 - std::pow(1.0 - a, e))), 4 * kEps) << a << " " << e;
    }
  // std::pow's special values that the renderer meets: 0^y = 0 (y > 0), x^0 = 1, 1^y = 1; a
  // subnormal base; results below the normal range (absolute 1e-300).
  EXPECT_EQ(slicing_pow(0.0, 32.0), 0.0);
  EXPECT_EQ(slicing_pow(0.0, 0.0), 1.0);
  EXPECT_EQ(slicing_pow(0.37, 0.0), 1.0);
  EXPECT_EQ(slicing_pow(1.0, 7.5), 1.0);
  EXPECT_NEAR(slicing_pow(1e-310, 0.5), std::pow(1e-310, 0.5), 1e-14 * std::pow(1e-310, 0.5));
  EXPECT_NEAR(slicing_pow(1e-10, 31.0), std::pow(1e-10, 31.0), 1e-300);
  EXPECT_EQ(slicing_pow(1e-10, 80.0), 0.0);  // 1e-800 underflows
  // (x slightly above 1, as max(n·h, 0) of two unit vectors may be)
  EXPECT_NEAR(slicing_pow(1.0 + 2 * kEps * 2, 32.0), std::pow(1.0 + 4 * kEps, 32.0), 1e-15);
  std::printf("worst error: %.3f of the bound\n", worst);
}

TEST(SlicingSpeed, SpecularPowerIsStdPowUpToRoundOffAndItsLanesGiveItsBits) {
  // slicing_specular_power: x^n for an integer n in [1, 1024] by binary exponentiation, each product
  // one rounding: the relative error roughly doubles with each squaring and grows by one rounding per
  // product, so it stays below 2 n eps (eps = 2^-53) against the long-double reference while the
  // result is normal; other exponents are slicing_pow's. Lanes give the scalar's bits. After rounding
  // to float (what the renderer keeps) it is std::pow's float but within 2 n eps of a float rounding
  // boundary: counted, a handful at most.
  constexpr double kEps = 0x1p-53;
  std::mt19937_64 rng(1729);
  std::uniform_real_distribution<double> U(0, 1);
  double worst = 0;  // in units of the bound
  int checked = 0, float_differs = 0;
  for (int n : {1, 2, 3, 5, 8, 16, 31, 32, 33, 64, 100, 128, 255, 1000, 1024}) {
    std::vector<double> x(4000), lanes(4000);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = i < 2 ? double(i) : i < 200 ? 1 - U(rng) * 1e-6 : U(rng);
    slicing_specular_power_lanes(x, double(n), lanes);
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double p = slicing_specular_power(x[i], double(n));
      ASSERT_EQ(std::bit_cast<std::uint64_t>(lanes[i]), std::bit_cast<std::uint64_t>(p)) << x[i] << "^" << n;
      const long double ref = std::pow((long double)x[i], (long double)n);
      if (!(ref > 0x1p-1000L)) {
        ASSERT_LE(p, 0x1p-990) << x[i] << "^" << n;  // below the normal range: tiny
        continue;
      }
      const double bound = 2 * n * kEps * double(ref);
      const double err = double(std::abs((long double)p - ref));
      worst = std::max(worst, err / bound);
      ASSERT_LE(err, bound) << x[i] << "^" << n;
      float_differs += float(p) != float(std::pow(x[i], double(n)));
      ++checked;
    }
  }
  EXPECT_EQ(slicing_specular_power(0.0, 32.0), 0.0);
  EXPECT_EQ(slicing_specular_power(1.0, 32.0), 1.0);
  EXPECT_EQ(slicing_specular_power(0.5, 10.0), 0x1p-10);  // exact powers of two stay exact
  // Not an integer in [1, 1024]: slicing_pow's bits.
  for (double y : {0.0, 0.5, 7.25, 1025.0, 2048.0})
    EXPECT_EQ(slicing_specular_power(0.83, y), slicing_pow(0.83, y)) << y;
  EXPECT_GT(checked, 40000);
  EXPECT_LE(float_differs, checked / 10000);
  std::printf("worst error: %.3f of the bound; %d of %d differ from std::pow's float\n", worst, float_differs, checked);
}

TEST(SlicingSpeed, CorrectedAlphaIsStdPowUpToRoundOffAndItsLanesGiveItsBits) {
  // slicing_corrected_alpha: a short series where a <= 1/32 and |e ln(1 - a)| <= 1/16, else 1 -
  // slicing_pow(1 - a, e). Against 1 - std::pow(1 - a, e) within (4 + e) eps absolute: the reference
  // itself rounds 1 - a (half an ulp, eps / 2, which the power scales by e) and rounds x^e and 1 - x^e
  // (about 2 eps); against the long-double value of the exact
  // -expm1(e log1p(-a)) (64-bit mantissa) the short branch is within 8 eps relative, where 1 - std::pow
  // may be off by far more relative (a cancellation at small a; the bound asserts the branch is taken
  // and is accurate, not that std::pow is worse).
  constexpr double kEps = 0x1p-53;
  std::vector<double> as, es;
  for (double e : {0.0, 0.25, 0.5, 0.93, 1.0, 1.07, 1.5, 2.0, 2.14, 4.0, 8.5, 40.0})
    for (int i = 0; i <= 3000; ++i) {
      // a: 0, log-spaced 1e-12 ... 1/32, both sides of 1/32, then up to 1
      const double a = i == 0      ? 0.0
                       : i <= 1500 ? std::pow(10.0, -12.0 + (12.0 + std::log10(1.0 / 32)) * (i - 1) / 1499)
                       : i <= 1510 ? std::nextafter(1.0 / 32, i < 1505 ? 0.0 : 1.0) * (1 + (i - 1505) * 1e-15)
                                   : (i - 1510) / 1490.0;
      as.push_back(std::min(a, 1.0)), es.push_back(e);
    }
  int short_branch = 0;
  for (std::size_t i = 0; i < as.size(); ++i) {
    const double a = as[i], e = es[i];
    const double got = slicing_corrected_alpha(a, e);
    ASSERT_LE(std::abs(got - (1.0 - std::pow(1.0 - a, e))), (4 + e) * kEps) << a << " " << e;
    const long double t = static_cast<long double>(e) * std::log1p(-static_cast<long double>(a));
    const long double exact = -std::expm1(t);
    if (a <= 1.0 / 32 && std::fabs(t) <= 1.0L / 16 && a > 0 && e > 0) {
      ++short_branch;
      ASSERT_LE(std::fabs(static_cast<long double>(got) - exact), 8 * kEps * exact) << a << " " << e;
    }
  }
  EXPECT_GT(short_branch, 8000);
  EXPECT_EQ(slicing_corrected_alpha(0.0, 1.3), 0.0);
  EXPECT_EQ(slicing_corrected_alpha(0.01, 0.0), 0.0);
  EXPECT_EQ(slicing_corrected_alpha(1.0, 0.7), 1.0);
  // The lanes: every element the scalar's bits, in packets that mix both branches (the order
  // interleaves small and large a, and exponents that push |t| past 1/16).
  std::vector<double> ma, me;
  for (std::size_t i = 0; i < as.size(); i += 7) ma.push_back(as[i]), me.push_back(es[(i * 13) % es.size()]);
  std::vector<double> out(ma.size());
  slicing_corrected_alpha_lanes(ma, me, out);
  for (std::size_t i = 0; i < ma.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint64_t>(out[i]), std::bit_cast<std::uint64_t>(slicing_corrected_alpha(ma[i], me[i])))
        << ma[i] << " " << me[i];
  EXPECT_THROW(slicing_corrected_alpha_lanes(ma, me, std::span<double>(out).first(3)), std::invalid_argument);
}

TEST(SlicingSpeed, FloatCorrectedAlphaIsExactToAFewFloatUlpsAndItsLanesGiveItsBits) {
  // slicing_corrected_alpha_f (the linear TF's per-sample correction in float): against the long-double
  // value of the exact -expm1(e log1p(-a)) at the same float a and e. The short branch rounds about
  // seven times (a - 2, the quotient s, the square, the products of t, the polynomial's fused steps, the
  // product t p), each within 2^-24 relative, and the series leave out < 2e-9 of the sum: within
  // kShort 2^-24 relative. The long branch is the double function (within (4 + e) 2^-53 of the exact
  // value absolute) rounded to float: within 2^-24 relative plus that.
  constexpr double kUlp = 0x1p-24, kEps = 0x1p-53;
  constexpr double kShort = 4;  // measured worst below; a term left out of either series exceeds it
  std::vector<float> as, es;
  for (float e : {0.0f, 0.25f, 0.5f, 0.93f, 1.0f, 1.07f, 1.5f, 2.0f, 2.14f, 4.0f, 8.5f, 40.0f})
    for (int i = 0; i <= 3000; ++i) {
      const double a = i == 0      ? 0.0
                       : i <= 1500 ? std::pow(10.0, -12.0 + (12.0 + std::log10(1.0 / 32)) * (i - 1) / 1499)
                       : i <= 1510 ? std::nextafter(1.0 / 32, i < 1505 ? 0.0 : 1.0) * (1 + (i - 1505) * 1e-7)
                                   : (i - 1510) / 1490.0;
      as.push_back(float(std::min(a, 1.0))), es.push_back(e);
    }
  // |t| up to the branch's 1/16, where the series' last terms matter most: a = 1 - e^(-τ/e).
  for (float e : {1.0f, 2.0f, 4.0f, 8.0f, 16.0f, 40.0f})
    for (int i = 0; i <= 500; ++i) {
      const double tau = (1.0 / 32) * (1 + i / 500.0);
      as.push_back(float(-std::expm1(-tau / double(e)))), es.push_back(e);
    }
  int short_branch = 0;
  double worst_short = 0;
  for (std::size_t i = 0; i < as.size(); ++i) {
    const float a = as[i], e = es[i];
    const float got = slicing_corrected_alpha_f(a, e);
    const long double t = a < 1 ? static_cast<long double>(e) * std::log1p(-static_cast<long double>(a)) : 0.0L;
    const long double exact = a < 1 ? -std::expm1(t) : e > 0 ? 1.0L : 0.0L;  // 0^0 = 1
    const double err = double(std::fabs(static_cast<long double>(got) - exact));
    if (a <= 1.0f / 32 && std::fabs(t) <= 1.0L / 16 && a > 0 && e > 0) {
      ++short_branch;
      worst_short = std::max(worst_short, err / (kUlp * double(exact)));
      ASSERT_LE(err, kShort * kUlp * double(exact)) << a << " " << e;
    } else {
      ASSERT_LE(err, kUlp * double(exact) + (4 + double(e)) * kEps) << a << " " << e;
    }
  }
  EXPECT_GT(short_branch, 8000);
  EXPECT_EQ(slicing_corrected_alpha_f(0.0f, 1.3f), 0.0f);
  EXPECT_EQ(slicing_corrected_alpha_f(0.01f, 0.0f), 0.0f);
  EXPECT_EQ(slicing_corrected_alpha_f(1.0f, 0.7f), 1.0f);
  // The lanes: every element the scalar's bits, in packets that mix both branches.
  std::vector<float> ma, me;
  for (std::size_t i = 0; i < as.size(); i += 7) ma.push_back(as[i]), me.push_back(es[(i * 13) % es.size()]);
  std::vector<float> out(ma.size());
  slicing_corrected_alpha_f_lanes(ma, me, out);
  for (std::size_t i = 0; i < ma.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint32_t>(out[i]),
              std::bit_cast<std::uint32_t>(slicing_corrected_alpha_f(ma[i], me[i])))
        << ma[i] << " " << me[i];
  EXPECT_THROW(slicing_corrected_alpha_f_lanes(ma, me, std::span<float>(out).first(3)), std::invalid_argument);
  std::printf("short branch: worst %.2f 2^-24 relative over %d cases\n", worst_short, short_branch);
}

TEST(SlicingSpeed, LinearTfInFloatIsTransferFunctionUpToFloatRoundOff) {
  // The renderer evaluates the linear kind in float (slicing_linear_tf_value: the sample is a float).
  // Against TransferFunction::evaluate at the same value in double: rounding a control point to float
  // moves it by 2^-24 |x| (the value by the slope times that), and the segment's arithmetic (v - a.x,
  // b.x - a.x, the quotient, b.y - a.y, the product and the sum) rounds six times: within
  // kTol 2^-24 (y_max + s_max x_max), s_max the steepest segment's slope. A wrong segment or t is off
  // by the slope times a segment's width. Values stay in [0, 1] (t in [0, 1]: the differences of the
  // rounded points), curves with shared and with separate control x, values at and between the points.
  constexpr double kTol = 8;
  std::mt19937 rng(20261129);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const bool shared = trial % 2 == 0;
    const int n = 1 + trial % 12;
    std::array<TfCurve, 4> curves;
    std::vector<double> xs;
    for (int c = 0; c < 4; ++c) {
      if (c == 0 || !shared) {
        xs.clear();
        for (int i = 0; i < n; ++i) xs.push_back(u01(rng) * 1.2 - 0.1);
        std::sort(xs.begin(), xs.end());
        xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
        if (trial % 7 == 3 && xs.size() > 1) xs[1] = std::nextafter(xs[0], 2.0);  // two points one ulp apart
      }
      for (double x : xs)
        curves[std::size_t(c)].points.emplace_back(x, trial % 5 == 0 ? double(u01(rng) < 0.5) : u01(rng));
    }
    const TransferFunction tf = TransferFunction::piecewise_linear(curves, "random");
    double y_max = 0, s_max = 0, x_max = 1;
    std::vector<double> steps;
    for (const auto& c : curves)
      for (std::size_t i = 0; i < c.points.size(); ++i) {
        y_max = std::max(y_max, std::abs(c.points[i].y()));
        x_max = std::max(x_max, std::abs(c.points[i].x()));
        if (i > 0) {
          const double dx = c.points[i].x() - c.points[i - 1].x();
          // A segment narrower than float's resolution there is a step: its rounded ends meet, so
          // the step moves by up to an ulp of x (the values next to it are left out below).
          if (dx > 4 * 0x1p-24 * x_max)
            s_max = std::max(s_max, std::abs(c.points[i].y() - c.points[i - 1].y()) / dx);
          else
            steps.push_back(c.points[i].x());
        }
      }
    const double bound = kTol * 0x1p-24 * (y_max + s_max * x_max);
    std::vector<float> vs;
    for (int i = 0; i <= 400; ++i) vs.push_back(float(-0.2 + 1.4 * i / 400.0));
    for (const auto& c : curves)
      for (const auto& p : c.points)
        for (float d : {-1.0f, 0.0f, 1.0f}) vs.push_back(std::nextafter(float(p.x()), d * 2.0f + float(p.x())));
    int near_steps = 0;
    for (float v : vs) {
      if (std::any_of(steps.begin(), steps.end(),
                      [&](double x) { return std::abs(double(v) - x) <= 8 * 0x1p-24 * x_max; })) {
        ++near_steps;
        continue;
      }
      const TfValue got = slicing_linear_tf_value(tf, v);
      const TfValue ref = tf.evaluate(double(v));
      ASSERT_LE(std::abs(got.alpha - ref.alpha), bound) << "trial " << trial << ", v " << v;
      for (int ch = 0; ch < 3; ++ch)
        ASSERT_LE(std::abs(got.rgb[ch] - ref.rgb[ch]), bound) << "trial " << trial << ", v " << v;
      ASSERT_GE(got.alpha, 0.0);
      ASSERT_LE(got.alpha, 1.0);
      ++checked;
    }
    if (trial % 7 == 3 && n > 1) {
      EXPECT_GT(near_steps, 0) << trial;
    }
  }
  EXPECT_GT(checked, 80000);
  EXPECT_THROW(slicing_linear_tf_value(skin_bone(), 0.5f), std::invalid_argument);
}

TEST(SlicingSpeed, ExactPowChangesPixelsOnlyByRoundOff) {
  // The constant TF's corrected α (slicing_corrected_alpha, double) differs from 1 - std::pow(1 - a, e)
  // by at most (4 + e) eps absolute (above), and the lit modes' specular power slicing_pow(base,
  // exponent) from std::pow by (16 + 4 |t|) eps relative; both are rounded to float for the float
  // compositing, where two doubles that close can fall on neighbouring floats (2^-24 relative). The
  // linear TF's corrected α is a float (slicing_corrected_alpha_f within 4 2^-24 of the exact value
  // relative, the exact_pow one within half an ulp). So the two α' (and lit colours) differ by at most
  // 4.5 2^-24 relative, and the over operator moves a pixel (and its opacity) by at most
  // Σ_k |δα'_k| T_k |c_k - C| <= 4.5 2^-24 c_max Σ_k α'_k T_k <= 4.5 2^-24 c_max, c_max <= 1.2 (the
  // colours times ambient + diffuse + specular): one ulp of the pixel plus kRoundOff 2^-24 per value.
  constexpr double kRoundOff = 8;
  const Volume& v = phantom();
  int differing = 0, compared = 0;
  double worst_ulps = 0;
  for (const Camera& cam : cameras(v.domain()))
    for (int variant = 0; variant < 6; ++variant) {
      // 0-3: the linear TF in Blend, MIP, combined with a mask, lit Blend; 4, 5: the constant TF
      // (its corrected α per ray and piece) in Blend and in combined with a mask of both kinds.
      SlicingSettings s = variant_settings(v, variant == 5 ? 3 : 0);
      if (variant < 4) s.tfs[0] = shared_points(6);
      if (variant == 5) s.mask = all_index_mask(v);
      if (variant < 4) {
        s.mode = variant == 1 ? SlicingMode::kMip : variant == 2 ? SlicingMode::kCombined : SlicingMode::kBlend;
        s.lit_blend = variant == 3;
      }
      if (variant == 2) s.mask = all_index_mask(v), s.tfs[2] = shared_points(12);
      s.exact_pow = true;
      const SlicingRenderer libm_renderer(v, s);
      const SlicingFrame libm = libm_renderer.render(cam);
      s.exact_pow = false;
      const SlicingFrame lanes = render_reusing_gradients(v, s, libm_renderer, cam);
      ASSERT_GT(libm.stats.classified, 0);
      for (const auto* img : {&libm.raw, &libm.alpha}) {
        const ImageF& other = img == &libm.raw ? lanes.raw : lanes.alpha;
        for (std::size_t i = 0; i < img->size(); ++i) {
          const float a = img->values()[i], b = other.values()[i];
          const float hi = std::max(std::abs(a), std::abs(b));
          const double tol = double(std::nextafter(hi, 2 * hi + 1) - hi) + kRoundOff * 0x1p-24;
          ASSERT_LE(std::abs(a - b), tol) << "variant " << variant << ", value " << i;
          worst_ulps = std::max(worst_ulps, double(std::abs(a - b)) / double(std::nextafter(hi, 2 * hi + 1) - hi));
          differing += a != b;
          ++compared;
        }
      }
    }
  EXPECT_GT(compared, 0);
  std::printf("%d of %d values differ, by at most %.1f float ulps\n", differing, compared, worst_ulps);
}

TEST(SlicingSpeed, BadCellSizeOrTerminationThresholdIsRefused) {
  const Volume& v = phantom();
  SlicingSettings s;
  s.tfs[0] = skin_bone();
  for (int cell : {0, 1, 3, 5, 32}) {
    s.skip_cell = cell;
    EXPECT_THROW(check_slicing_settings(v, s), InputError) << cell;
  }
  s.skip_cell = 4;
  for (double t : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    s.early_termination = t;
    EXPECT_THROW(check_slicing_settings(v, s), InputError) << t;
  }
  s.early_termination = 0.99;
  EXPECT_NO_THROW(check_slicing_settings(v, s));
}

}  // namespace
}  // namespace meltlab::render
