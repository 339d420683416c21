// Seed 003's slicing renderer (render/slicing/) against the spec's §5 identities: convergence of
// Blend to the ray caster (the one volume integrator's TF model) as QC -> 0, the gradient estimator
// (exact on linear fields, radius 2 against 1, 8 against 4 bits), the mask's semantics, compositing
// closed forms, the bloom chain's identities, piecewise-linear TFs and the gradient cache.

#include <meltlab/core/error.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/slicing/bloom.h>
#include <meltlab/render/slicing/gradient_volume.h>
#include <meltlab/render/slicing/mask_volume.h>
#include <meltlab/render/slicing/slicing_renderer.h>
#include <meltlab/render/slicing/test_fields.h>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "test_files.h"

namespace meltlab::render {
namespace {

Camera camera_30deg(int w, int h, const Box3& box, const Eigen::Vector3d& dir) {
  const double fy = 0.5 * h / std::tan(15.0 * M_PI / 180.0);
  return Pinhole::look_at(w, h, fy, box.centre() + dir, box.centre(), Eigen::Vector3d(0, 0, 1));
}

TransferFunction linear_tf(double r, double g, double b, double a_max) {
  std::array<TfCurve, 4> c;
  c[0].points = {{0.0, r}, {1.0, r}};
  c[1].points = {{0.0, g}, {1.0, g}};
  c[2].points = {{0.0, b}, {1.0, b}};
  c[3].points = {{0.2, 0.0}, {0.6, a_max}, {1.0, a_max}};
  return TransferFunction::piecewise_linear(c);
}

double rmse(const ImageF& a, const ImageF& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += std::pow(double(a.values()[i]) - double(b.values()[i]), 2);
  return std::sqrt(s / double(a.size()));
}

// ---------------------------------------------------------------- transfer functions

TEST(SlicingTf, PiecewiseLinearCurvesInterpolateAndClampAtTheEnds) {
  const TransferFunction tf = linear_tf(0.25, 0.5, 1.0, 0.8);
  EXPECT_EQ(tf.kind(), TfKind::kPiecewiseLinear);
  EXPECT_DOUBLE_EQ(tf.evaluate(0.0).alpha, 0.0);
  EXPECT_DOUBLE_EQ(tf.evaluate(0.4).alpha, 0.4);  // halfway between (0.2, 0) and (0.6, 0.8)
  EXPECT_DOUBLE_EQ(tf.evaluate(2.0).alpha, 0.8);
  EXPECT_DOUBLE_EQ(tf.evaluate(0.3).rgb.y(), 0.5);
  EXPECT_FALSE(tf.visible_at(0.1));
  EXPECT_TRUE(tf.visible_at(0.21));
  EXPECT_FALSE(tf.visible_in(-1, 0.2));
  EXPECT_TRUE(tf.visible_in(0.1, 0.3));
  // A constant TF answers evaluate too (colour / 255).
  const TransferFunction c = TransferFunction::skull();
  EXPECT_DOUBLE_EQ(c.evaluate(100).rgb.x(), 1.0);
  EXPECT_DOUBLE_EQ(c.evaluate(10).alpha, 0.0);
  // The ray caster's kernel tables ranges: it refuses the linear kind instead of rendering nothing.
  VolumeRenderSettings rc;
  rc.model = OpticalModel::kTransferFunction;
  rc.tf.table = tf;
  rc.step_rule = StepRule::kFixedStep;
  rc.step = 0.5;
  Volume v = Volume::allocate(4, 4, 4, SampleType::kFloat32);
  EXPECT_THROW(check_volume_render_settings(v, rc), InputError);
  rc.tf.table = c;
  EXPECT_NO_THROW(check_volume_render_settings(v, rc));
  std::array<TfCurve, 4> bad;
  bad[3].points = {{0.5, 0.1}, {0.5, 0.2}};
  EXPECT_THROW(TransferFunction::piecewise_linear(bad), InputError);
  bad[3].points = {{0.5, 1.5}};
  EXPECT_THROW(TransferFunction::piecewise_linear(bad), InputError);
}

// ---------------------------------------------------------------- gradients

Volume linear_field(const Eigen::Vector3d& a, int n) {
  Volume v = Volume::allocate(n, n, n, SampleType::kFloat32);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) v.set_value(i, j, k, a.dot(Eigen::Vector3d(i, j, k)));
  return v;
}

TEST(SlicingGradient, ExactOnLinearFields) {
  EXPECT_NEAR(gradient_normaliser(1, GradientNeighbourhood::kCube), 2 + 8 / std::sqrt(2.0) + 8 / std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(gradient_normaliser(1, GradientNeighbourhood::kCube), 12.276, 5e-4);  // the spec's printed value
  EXPECT_NEAR(gradient_normaliser(2, GradientNeighbourhood::kCube), 98.311, 5e-4);
  const Eigen::Vector3d a(0.013, -0.007, 0.021);
  const int n = 12;
  const Volume v = linear_field(a, n);
  for (int r : {1, 2}) {
    const double k = gradient_normaliser(r, GradientNeighbourhood::kCube);
    const auto g = estimate_gradients(v, r, GradientNeighbourhood::kCube);
    for (int z = r; z < n - r; ++z)
      for (int y = r; y < n - r; ++y)
        for (int x = r; x < n - r; ++x) {
          const Eigen::Vector3d got = g[std::size_t(x + n * (y + n * z))].cast<double>();
          // float sums of up to 124 terms of size ~0.3: a few float ulps of the result.
          EXPECT_LT((got - k * a).norm(), 2e-5 * k * a.norm()) << "r " << r << " at " << x << "," << y << "," << z;
        }
  }
}

// Mean angles (degrees) over the field's band: the raw estimate against the analytic gradient, and
// the decoded (quantised) estimate against the raw one (the quantisation error alone).
struct AngleErrors {
  double estimator = 0, quantisation = 0;
};
AngleErrors angle_errors(const Volume& v, TestField field, const GradientOptions& o) {
  const int n = v.nx();
  const auto raw = estimate_gradients(v, o.radius, o.neighbourhood);
  const GradientVolume enc = encode_gradients(raw, v.dims(), o);
  auto angle = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
  };
  AngleErrors e;
  int count = 0;
  for (int k = 2; k < n - 2; ++k)
    for (int j = 2; j < n - 2; ++j)
      for (int i = 2; i < n - 2; ++i) {
        Eigen::Vector3d truth;
        const double sd = test_field_distance(field, n, Eigen::Vector3d(i, j, k), &truth);
        if (std::abs(sd) > 0.75) continue;  // the smooth step's band (its width is 2 voxels)
        const Eigen::Vector3d g = raw[std::size_t(i + n * (j + n * k))].cast<double>();
        e.estimator += angle(g, -truth);  // f falls along the distance gradient
        e.quantisation += angle(enc.decoded(i, j, k), g);
        ++count;
      }
  e.estimator /= count;
  e.quantisation /= count;
  return e;
}

Volume with_noise(Volume v, double sigma, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, sigma);
  for (int k = 0; k < v.nz(); ++k)
    for (int j = 0; j < v.ny(); ++j)
      for (int i = 0; i < v.nx(); ++i) v.set_value(i, j, k, double(v.value(i, j, k)) + g(rng));
  return v;
}

TEST(SlicingGradient, RadiusOneAgainstTwoAndEightBitsAgainstFour) {
  for (TestField field : {TestField::kSphere, TestField::kTorus}) {
    const char* name = field == TestField::kSphere ? "sphere" : "torus";
    const Volume clean = make_test_field(field, 48);
    const Volume noisy = with_noise(make_test_field(field, 48), 0.05, 11);  // copies share samples: a new one
    const GradientOptions o1{1, GradientNeighbourhood::kCube, 8}, o2{2, GradientNeighbourhood::kCube, 8};
    const AngleErrors c1 = angle_errors(clean, field, o1), c2 = angle_errors(clean, field, o2);
    const AngleErrors n1 = angle_errors(noisy, field, o1), n2 = angle_errors(noisy, field, o2);
    std::printf(
        "field %s: mean angular error, noise-free: radius 1 %.4f deg, radius 2 %.4f deg; noise sigma 0.05: "
        "radius 1 %.4f deg, radius 2 %.4f deg\n",
        name, c1.estimator, c2.estimator, n1.estimator, n2.estimator);
    // Measured (and reported, not hidden): on the noise-free 2-voxel smooth step radius 1 is the
    // more accurate (radius 2 reaches past the band into the flat parts); with noise, radius 2's
    // 124 samples average it down and win, which is what the source saw on CT data.
    EXPECT_LT(c1.estimator, 3.0);  // measured 1.8-2.1 deg (sphere, torus): a broken estimator is tens of degrees off
    EXPECT_LT(c2.estimator, 3.0);
    EXPECT_LT(n2.estimator, n1.estimator);
    // Quantisation alone (decoded against raw, radius 2): about 1/17 for steps 1/255 against 1/15.
    GradientOptions o4 = o2;
    o4.bits = 4;
    const double q8 = c2.quantisation, q4 = angle_errors(clean, field, o4).quantisation;
    std::printf("field %s: quantisation error 8-bit %.4f deg, 4-bit %.4f deg, ratio %.4f (1/17 = %.4f)\n", name, q8, q4,
                q8 / q4, 1.0 / 17);
    // A factor 1.5 either way: the angle is linear in the step only while it is small, and
    // the 4-bit rounding of the weaker gradients in the band is not small.
    EXPECT_GT(q8 / q4, 1.0 / (17 * 1.5));
    EXPECT_LT(q8 / q4, 1.5 / 17);
  }
}

TEST(SlicingGradient, RadiusTwoBeatsRadiusOneOnTheCleanFieldsWithTheBallNeighbourhood) {
  // The spec's target (§5: radius 2 below radius 1 on the sphere field) holds noise-free for the
  // ball neighbourhood. The cube's radius-2 stencil is anisotropic (its corners weigh the
  // diagonals 2√3 voxels out, where the 2-voxel step is flat), so on a non-linear profile its
  // direction errs more than radius 1's (the test above); the ball (|o| <= 2: 32 offsets) is
  // nearly isotropic and reads the step's slope on both sides. Measured (printed below; a NumPy
  // model of the estimator gave the same digits): sphere ball radius 2 0.80°, cube radius 1 1.83°,
  // ball radius 1 (the 6 face neighbours) 3.43°, cube radius 2 2.52°; torus 0.74°, 2.03°, 3.74°.
  for (TestField field : {TestField::kSphere, TestField::kTorus}) {
    const Volume clean = make_test_field(field, 48);
    const GradientOptions b1{1, GradientNeighbourhood::kBall, 8}, b2{2, GradientNeighbourhood::kBall, 8};
    const GradientOptions c1{1, GradientNeighbourhood::kCube, 8};
    const double e_b1 = angle_errors(clean, field, b1).estimator, e_b2 = angle_errors(clean, field, b2).estimator;
    const double e_c1 = angle_errors(clean, field, c1).estimator;
    std::printf("field %s, noise-free: ball radius 1 %.4f deg, ball radius 2 %.4f deg, cube radius 1 %.4f deg\n",
                field == TestField::kSphere ? "sphere" : "torus", e_b1, e_b2, e_c1);
    EXPECT_LT(e_b2, e_b1);
    EXPECT_LT(e_b2, e_c1) << "ball radius 2 should also beat the default cube radius 1";
  }
}

TEST(SlicingGradient, EncodedMagnitudeIsAtMostOneAndTheCacheRoundTrips) {
  const Volume v = make_test_field(TestField::kSphere, 20);
  const GradientOptions o{2, GradientNeighbourhood::kCube, 8};
  const GradientVolume g = build_gradient_volume(v, o);
  double worst = 0;
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) worst = std::max(worst, g.decoded(i, j, k).norm());
  // |2e - 1| <= 1 before rounding; rounding moves each component by at most 1/255.
  EXPECT_LE(worst, 1.0 + std::sqrt(3.0) / 255);
  EXPECT_GT(worst, 0.99);  // the largest gradient is encoded at full scale
  test::TempFolder dir;
  const GradientVolume first = cached_gradient_volume(v, o, dir.path());
  EXPECT_FALSE(first.from_cache);
  const GradientVolume second = cached_gradient_volume(v, o, dir.path());
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.encoded, g.encoded);
  EXPECT_EQ(second.max_magnitude, g.max_magnitude);
  // A different radius is a different file; a truncated file is recomputed.
  const GradientOptions o1{1, GradientNeighbourhood::kCube, 8};
  EXPECT_NE(gradient_cache_name(v, o), gradient_cache_name(v, o1));
  const auto file = dir.path() / gradient_cache_name(v, o);
  std::filesystem::resize_file(file, 100);
  const GradientVolume third = cached_gradient_volume(v, o, dir.path());
  EXPECT_FALSE(third.from_cache);
  EXPECT_EQ(third.encoded, g.encoded);
  EXPECT_TRUE(cached_gradient_volume(v, o, dir.path()).from_cache);
  EXPECT_THROW(build_gradient_volume(v, GradientOptions{2, GradientNeighbourhood::kCube, 6}), InputError);
}

// ---------------------------------------------------------------- compositing closed forms

TEST(SlicingCompositing, ClosedFormsForNConstantSlices) {
  // The accumulator is float: each step rounds its products and sum (within 2^-24 relative each, of
  // values <= 1), so after N steps the sums are within 3 N 2^-24 of the closed forms (computed in
  // double from the same float c and a).
  const Eigen::Vector3f c(0.9f, 0.4f, 0.1f);
  const float a = 0.07f;
  const Eigen::Vector3d cd = c.cast<double>();
  for (int N : {1, 5, 40}) {
    SliceAccumulator over, add, comb;
    for (int i = 0; i < N; ++i) {
      over.blend_over(c, a);
      add.blend_additive(c, a);
      comb.combined(c, a, a);
    }
    const double tol = 3 * N * 0x1p-24;
    const double expected = 1 - std::pow(1 - double(a), N);
    EXPECT_NEAR((over.C.cast<double>() - cd * expected).norm(), 0, tol);
    EXPECT_NEAR(over.A, expected, tol);
    EXPECT_NEAR((add.C.cast<double>() - N * double(a) * cd).norm(), 0, tol);
    EXPECT_GT((over.C.cast<double>() - cd * (1 - std::pow(1 - double(a), N + 1))).norm(),
              tol);        // one step more is seen
    EXPECT_EQ(comb.C, c);  // exactly: every sample is as hard as the hardest
  }
}

TEST(SlicingCompositing, RenderedConstantVolumeMatchesTheOverClosedForm) {
  // A constant volume seen head-on: the centre pixel's ray is n (cos ψ = 1), so N samples of the
  // same (c, a') with a' = 1 - (1 - a)^(Δd / h0).
  Volume v = Volume::allocate(8, 8, 8, SampleType::kFloat32);
  for (int k = 0; k < 8; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) v.set_value(i, j, k, 0.5);
  v.set_placement(SamplePlacement::kNodes);
  v.fit_to_box(Box3{Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(7)});
  const Box3 box = v.domain();
  SlicingSettings s;
  s.value_range = std::make_pair(0.0, 1.0);
  s.tfs[0] = linear_tf(0.3, 0.6, 0.9, 0.05);  // at 0.5: α = 0.05 * 0.3 / 0.4 = 0.0375
  const double a = 0.0375;
  for (double qc : {0.5, 1.0, 2.5}) {
    s.quality_class = qc;
    const Camera cam = camera_30deg(33, 33, box, Eigen::Vector3d(0, -30, 0));
    const SlicingFrame f = render_slicing(v, cam, s);
    const CameraRay r = RayGenerator(cam).generate_ray(16, 16);
    const SliceStack st = slice_stack(box, r.origin, qc * 1.0);
    const RaySlices rs = ray_slices(st, box, r.origin, r.direction);
    ASSERT_NEAR(rs.cos_psi, 1.0, 1e-12);
    const int N = rs.k_last - rs.k_first + 1;
    EXPECT_NEAR(N, 7.0 / qc, 1.0);
    const double ac = 1 - std::pow(1 - a, qc);
    const double expected = 1 - std::pow(1 - ac, N);
    // float storage of the image: relative 1e-6.
    EXPECT_NEAR(double(f.raw.at(16, 16, 0)), 0.3 * expected, 1e-6);
    EXPECT_NEAR(double(f.alpha.at(16, 16)), expected, 1e-6);
  }
}

// ---------------------------------------------------------------- convergence to the ray caster

TEST(SlicingRender, BlendConvergesToTheRayCasterAsQualityClassFalls) {
  const Volume v = make_test_field(TestField::kTorus, 40);
  // One piecewise-constant TF for both renderers (the ray caster reads that kind): a soft shell.
  std::vector<TfRange> ranges(2);
  ranges[0] = {0.2, 0.6, false, true, Eigen::Vector3d(200, 120, 40), 0.08};
  ranges[1] = {0.6, 1.0, false, true, Eigen::Vector3d(60, 160, 255), 0.25};
  const TransferFunction tf(ranges, "test");
  const Box3 box = v.domain();
  const Camera cam = camera_30deg(64, 48, box, Eigen::Vector3d(1.6, -2.2, 1.3));
  VolumeRenderSettings rc;
  rc.model = OpticalModel::kTransferFunction;
  rc.tf.table = tf;
  rc.tf.shading.enabled = false;
  rc.step_rule = StepRule::kFixedStep;
  const double h0 = v.spacing().minCoeff();
  rc.step = h0 / 16;  // the reference: 16 samples per voxel along every ray
  const VolumeFrame ref = render_volume(v, cam, rc);
  ImageF ref_rgb(ref.radiance.width(), ref.radiance.height(), 3);
  for (std::size_t i = 0; i < ref_rgb.size(); ++i) ref_rgb.values()[i] = ref.radiance.values()[i];
  SlicingSettings s;
  s.value_range = std::make_pair(0.0, 1.0);
  s.tfs[0] = tf;
  double prev = 1e300;
  std::vector<double> errs;
  for (double qc : {4.0, 2.0, 1.0, 0.5, 0.25}) {
    s.quality_class = qc;
    const SlicingFrame f = render_slicing(v, cam, s);
    const double e = rmse(f.raw, ref_rgb);
    errs.push_back(e);
    std::printf("QC %.2f: RMSE against the ray caster (step h0/16) %.6f\n", qc, e);
    EXPECT_LT(e, prev) << "QC " << qc;
    prev = e;
  }
  // Not only monotone: the finest QC is far closer than the coarsest.
  EXPECT_LT(errs.back(), 0.25 * errs.front());
}

TEST(SlicingRender, SerialAndParallelFramesAreBitwiseEqualInEveryMode) {
  const Volume v = make_test_field(TestField::kSphere, 40);  // 5³ cells of 8³: the corners are empty
  const Camera cam = camera_30deg(40, 30, v.domain(), Eigen::Vector3d(1.5, -2.0, 1.0));
  SlicingSettings s;
  s.value_range = std::make_pair(0.0, 1.0);
  s.tfs[0] = linear_tf(1.0, 0.8, 0.6, 0.4);
  for (SlicingMode m : {SlicingMode::kBlend, SlicingMode::kMip, SlicingMode::kCombined}) {
    s.mode = m;
    s.parallel = true;
    const SlicingFrame a = render_slicing(v, cam, s);
    s.parallel = false;
    const SlicingFrame b = render_slicing(v, cam, s);
    EXPECT_EQ(a.raw, b.raw) << slicing_mode_name(m);
    EXPECT_GT(a.stats.classified, 0);
    // Empty-space skipping changes no pixel (it only leaves out samples of α = 0).
    s.skip_empty = false;
    const SlicingFrame c = render_slicing(v, cam, s);
    s.skip_empty = true;
    EXPECT_EQ(a.raw, c.raw) << slicing_mode_name(m);
    EXPECT_GT(a.stats.skipped, 0);
    EXPECT_EQ(c.stats.skipped, 0);
  }
}

// render_into reuses a frame's images: the same bits as render() into a fresh frame, whether the
// frame held this camera's last image (of another mode, with bloom), another size, or nothing;
// and the stats start from zero each frame.
TEST(SlicingRender, FramesRenderedIntoUsedImagesEqualFreshFrames) {
  const Volume v = make_test_field(TestField::kSphere, 40);
  const Camera cam = camera_30deg(40, 30, v.domain(), Eigen::Vector3d(1.5, -2.0, 1.0));
  const Camera small = camera_30deg(17, 11, v.domain(), Eigen::Vector3d(1.5, -2.0, 1.0));
  SlicingSettings s;
  s.value_range = std::make_pair(0.0, 1.0);
  s.tfs[0] = linear_tf(1.0, 0.8, 0.6, 0.4);
  SlicingSettings bloom = s;
  bloom.mode = SlicingMode::kCombined;
  bloom.post.enabled = true;
  bloom.post.adjust = ColorAdjust{1.2, 0.05, 1.5};
  const SlicingRenderer other(v, bloom);
  for (SlicingMode m : {SlicingMode::kBlend, SlicingMode::kMip, SlicingMode::kCombined}) {
    s.mode = m;
    const SlicingRenderer r(v, s);
    const SlicingFrame fresh = r.render(cam);
    SlicingFrame used;
    other.render_into(cam, used);  // this size, other pixels
    r.render_into(cam, used);
    SlicingFrame resized = other.render(small);  // another size
    r.render_into(cam, resized);
    for (const SlicingFrame* f : {&used, &resized}) {
      EXPECT_EQ(f->raw, fresh.raw) << slicing_mode_name(m);
      EXPECT_EQ(f->alpha, fresh.alpha) << slicing_mode_name(m);
      EXPECT_EQ(f->rgb, fresh.rgb) << slicing_mode_name(m);
      EXPECT_EQ(f->stats.samples, fresh.stats.samples) << slicing_mode_name(m);
      EXPECT_EQ(f->stats.rays, fresh.stats.rays) << slicing_mode_name(m);
    }
    EXPECT_NE(other.render(cam).rgb, fresh.rgb) << "the first image must differ for the test to mean anything";
  }
}

// A post chain that only clamps (no bloom, the identity adjustment) is applied as the pixels are
// written: the frame's rgb is the chain applied to its raw image, bit for bit, in the packets and one
// ray at a time, with values above 1 (additive, a bright background) that the clamp changes.
TEST(SlicingRender, ClampOnlyPostChainIsWrittenWithThePixels) {
  const Volume v = make_test_field(TestField::kSphere, 24);
  const Camera cam = camera_30deg(40, 30, v.domain(), Eigen::Vector3d(1.5, -2.0, 1.0));
  SlicingSettings s;
  s.value_range = std::make_pair(0.0, 1.0);
  s.tfs[0] = linear_tf(1.0, 0.8, 0.6, 0.4);
  s.blend = BlendOperator::kAdditive;
  s.background = Eigen::Vector3d(0.9, 0.95, 1.0);
  ASSERT_TRUE(bloom_is_clamp(s.post));
  for (const bool simd : {false, true}) {
    s.simd = simd;
    const SlicingFrame f = SlicingRenderer(v, s).render(cam);
    EXPECT_EQ(f.rgb, apply_bloom(f.raw, s.post)) << simd;
    EXPECT_GT(*std::max_element(f.raw.values().begin(), f.raw.values().end()), 1.0f) << "the clamp must matter";
  }
  // The chain's settings are still checked when the chain only clamps.
  s.post.sigma = 0;
  EXPECT_THROW(SlicingRenderer(v, s).render(cam), InputError);
}

// ---------------------------------------------------------------- the mask

TEST(SlicingMask, AllOnesEqualsUnmaskedAndIndexZeroEqualsZeroAlpha) {
  const Volume v = make_test_field(TestField::kTorus, 32);
  const Box3 box = v.domain();
  const Camera cam = camera_30deg(48, 36, box, Eigen::Vector3d(1.4, -2.0, 1.2));
  SlicingSettings s;
  s.value_range = std::make_pair(0.0, 1.0);
  s.tfs[0] = linear_tf(1.0, 0.7, 0.3, 0.5);
  for (SlicingMode m : {SlicingMode::kBlend, SlicingMode::kMip, SlicingMode::kCombined}) {
    s.mode = m;
    s.mask = MaskVolume();
    const SlicingFrame unmasked = render_slicing(v, cam, s);
    s.mask = MaskVolume({17, 13, 11}, box, 1);
    EXPECT_EQ(render_slicing(v, cam, s).raw, unmasked.raw) << slicing_mode_name(m);
    // A cut (index 0) against the same region with a TF of α = 0 everywhere.
    MaskEdit cut;
    cut.shape = MaskShape::kEllipsoid;
    cut.centre = Eigen::Vector3d(0.6, 0.45, 0.55);
    cut.half_size = Eigen::Vector3d(0.3, 0.2, 0.25);
    cut.rotate_deg = Eigen::Vector3d(10, 20, 30);
    cut.index = 0;
    s.mask.apply(cut);
    const SlicingFrame cut_frame = render_slicing(v, cam, s);
    MaskEdit transparent = cut;
    transparent.index = 3;
    s.mask = MaskVolume({17, 13, 11}, box, 1);
    s.mask.apply(transparent);
    s.tfs[2] = TransferFunction();  // α = 0 everywhere
    const SlicingFrame zero_alpha = render_slicing(v, cam, s);
    EXPECT_EQ(cut_frame.raw, zero_alpha.raw) << slicing_mode_name(m);
    EXPECT_NE(cut_frame.raw, unmasked.raw) << "the cut must change the image";
  }
}

TEST(SlicingMask, IndexLookupIsTheWorldLookupUpToFloatCellFaces) {
  // MaskIndexLookup (the renderer's lookup from a sample's stencil corner i and weight w) against
  // MaskVolume::lookup of the world point origin + (i + w) spacing, over random volumes (origin,
  // spacing), mask boxes that are not the volume's, mask resolutions and contents, and samples in
  // and around the box (clamped cells). The two may differ only where the exact mask coordinate
  // lies within kFace cells of a cell face: the float rounding of i + w (2^-24 |g|), of s and o
  // (2^-24 each, times |g| and 1) and of the product and sum, about 2^-22 (|g| s + |o|) at most.
  std::mt19937 rng(20261129);
  std::uniform_real_distribution<double> U(0, 1);
  std::int64_t checked = 0, near_face = 0, differ = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const std::array<int, 3> dims{2 + int(U(rng) * 300), 2 + int(U(rng) * 300), 2 + int(U(rng) * 200)};
    const Eigen::Vector3d origin(200 * U(rng) - 100, 200 * U(rng) - 100, 200 * U(rng) - 100);
    const Eigen::Vector3d spacing(0.1 + 3 * U(rng), 0.1 + 3 * U(rng), 0.1 + 3 * U(rng));
    Box3 box;
    box.lo = origin - Eigen::Vector3d::Constant(2 * U(rng));
    box.hi = origin + spacing.cwiseProduct(Eigen::Vector3d(dims[0] - 1, dims[1] - 1, dims[2] - 1)) +
             Eigen::Vector3d::Constant(2 * U(rng));
    MaskVolume mask({1 + int(U(rng) * 60), 1 + int(U(rng) * 60), 1 + int(U(rng) * 60)}, box, 1);
    for (int e = 0; e < 8; ++e) {
      MaskEdit edit;
      edit.centre = Eigen::Vector3d(U(rng), U(rng), U(rng));
      edit.half_size = Eigen::Vector3d(0.02 + 0.2 * U(rng), 0.02 + 0.2 * U(rng), 0.02 + 0.2 * U(rng));
      edit.index = int(U(rng) * 5);
      mask.apply(edit);
    }
    const MaskIndexLookup lut = mask.index_lookup(origin, spacing);
    const auto n = mask.dims();
    for (int q = 0; q < 4000; ++q) {
      int i[3];
      float w[3];
      bool near = false;
      for (int a = 0; a < 3; ++a) {
        i[a] = -2 + int(U(rng) * (dims[std::size_t(a)] + 3));
        w[a] = float(int(U(rng) * 16777216.0)) * 0x1p-24f;
        // Half the samples on a cell face of the mask (then rounded to the weight's 2^-24).
        if (q % 2 == 0) {
          const double face = std::floor(U(rng) * (n[std::size_t(a)] + 1));
          const double g = ((face / n[std::size_t(a)]) * box.size()[a] + box.lo[a] - origin[a]) / spacing[a];
          i[a] = int(std::floor(g));
          w[a] = float(std::floor((g - i[a]) * 16777216.0)) * 0x1p-24f;
        }
        const double g = i[a] + double(w[a]);
        const double u = ((origin[a] + g * spacing[a]) - box.lo[a]) / box.size()[a] * n[std::size_t(a)];
        const double kFace = 0x1p-21 * (std::abs(g) * spacing[a] * n[std::size_t(a)] / box.size()[a] +
                                        std::abs(origin[a] - box.lo[a]) * n[std::size_t(a)] / box.size()[a] + 1);
        near = near || std::abs(u - std::round(u)) <= kFace;
      }
      const Eigen::Vector3d p =
          origin + spacing.cwiseProduct(Eigen::Vector3d(i[0] + double(w[0]), i[1] + double(w[1]), i[2] + double(w[2])));
      const int world = mask.lookup(p), index = lut.lookup(i[0], i[1], i[2], w[0], w[1], w[2]);
      ++checked;
      near_face += near;
      if (world != index) {
        ++differ;
        EXPECT_TRUE(near) << "trial " << trial << " sample " << q << ": index lookup " << index << ", world " << world;
      }
    }
  }
  std::printf("%lld samples, %lld within the float tolerance of a cell face, %lld differ there\n", (long long)checked,
              (long long)near_face, (long long)differ);
  EXPECT_GT(near_face, checked / 4) << "the faces must be exercised";
}

TEST(SlicingMask, ResolutionChangesOnlyPixelsNearRegionBoundaries) {
  const Volume v = make_test_field(TestField::kSphere, 32);
  const Box3 box = v.domain();
  const Eigen::Vector3d dir(0.9, -2.1, 1.1);
  const Camera cam = camera_30deg(64, 48, box, dir);
  SlicingSettings s;
  s.value_range = std::make_pair(0.0, 1.0);
  s.tfs[0] = linear_tf(1.0, 0.7, 0.3, 0.5);
  // The region: a slab x > 0.37 cut away (not aligned with either resolution's cells).
  MaskEdit slab;
  slab.shape = MaskShape::kBox;
  slab.centre = Eigen::Vector3d(0.37 + 0.5, 0.5, 0.5);
  slab.half_size = Eigen::Vector3d(0.5, 1, 1);
  slab.index = 0;
  std::vector<ImageF> frames;
  for (int res : {24, 61}) {
    s.mask = MaskVolume({res, res, res}, box, 1);
    s.mask.apply(slab);
    frames.push_back(render_slicing(v, cam, s).raw);
  }
  // A pixel may change only if its ray passes within one coarse cell (in x) of the plane x = 0.37
  // inside the box: the mask's nearest lookup moves the boundary by less than a cell.
  const double cell = 1.0 / 24;
  const RayGenerator rays(cam);
  int changed = 0, allowed_but_same = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      bool differs = false;
      for (int c = 0; c < 3; ++c) differs = differs || frames[0].at(x, y, c) != frames[1].at(x, y, c);
      const CameraRay r = rays.generate_ray(x, y);
      const auto iv = intersect_box(box, r.origin, r.direction);
      bool near = false;
      if (iv) {
        const double xa = r.at(iv->t0).x(), xb = r.at(iv->t1).x();
        near = std::min(xa, xb) - cell <= 0.37 && std::max(xa, xb) + cell >= 0.37;
      }
      if (differs) {
        ++changed;
        EXPECT_TRUE(near) << "pixel " << x << "," << y << " changed far from the region boundary";
      } else if (near) {
        ++allowed_but_same;
      }
    }
  EXPECT_GT(changed, 0) << "the resolution must matter somewhere (else the test proves nothing)";
  EXPECT_LT(changed, 64 * 48 / 2);
}

// ---------------------------------------------------------------- bloom

ImageF random_image(int w, int h, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0, 1);
  ImageF im(w, h, 3);
  for (float& x : im.values()) x = float(scale) * U(rng);
  return im;
}

TEST(SlicingBloom, BelowThresholdIsTheAdjustedImage) {
  const ImageF im = random_image(40, 30, 0.6, 1);  // after contrast 1.1 every channel < 0.7, so every luminance is
  BloomSettings b;
  b.enabled = true;
  b.adjust = ColorAdjust{1.1, 0.0, 1.0};
  ImageF dim = adjust_colours(im, b.adjust);
  double mx = 0;
  for (float x : dim.values()) mx = std::max(mx, double(x));
  ASSERT_LT(mx, 0.7);
  EXPECT_EQ(apply_bloom(im, b), dim);
  b.enabled = false;
  EXPECT_EQ(apply_bloom(im, BloomSettings{}), im);  // identity adjustment, values in [0, 1]
}

// The chain into a used image (another size, or this size with other values) equals the chain
// into a fresh one, with and without bloom; a fourth channel is copied, not adjusted.
TEST(SlicingBloom, IntoAUsedImageEqualsIntoAFreshOne) {
  const ImageF im = random_image(40, 30, 1.3, 2);  // values above 1: the clamp matters
  for (const bool enabled : {false, true})
    for (const ColorAdjust& a : {ColorAdjust{}, ColorAdjust{1.2, 0.05, 1.5}}) {
      BloomSettings b;
      b.enabled = enabled;
      b.adjust = a;
      const ImageF fresh = apply_bloom(im, b);
      ImageF same_size = random_image(40, 30, 1.0, 3), other_size = random_image(7, 5, 1.0, 4);
      apply_bloom(im, b, same_size);
      apply_bloom(im, b, other_size);
      EXPECT_EQ(same_size, fresh) << enabled;
      EXPECT_EQ(other_size, fresh) << enabled;
    }
  ImageF rgba(6, 4, 4);
  for (std::size_t i = 0; i < rgba.size(); ++i) rgba.values()[i] = 0.5f * float(i % 5);
  ImageF out;
  adjust_colours(rgba, ColorAdjust{}, out);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) {
      for (int c = 0; c < 3; ++c) EXPECT_EQ(out.at(x, y, c), std::clamp(rgba.at(x, y, c), 0.0f, 1.0f));
      EXPECT_EQ(out.at(x, y, 3), rgba.at(x, y, 3));
    }
}

TEST(SlicingBloom, WeightsSumToOneAndDownsampleKeepsTheMean) {
  for (double sigma : {0.5, 1.0, 2.0, 3.7}) {
    const auto w = gaussian_weights(sigma);
    double sum = 0;
    for (double x : w) sum += x;
    EXPECT_NEAR(sum, 1.0, 1e-15);
    EXPECT_EQ(int(w.size()), 2 * int(std::ceil(3 * sigma)) + 1);
  }
  const ImageF im = random_image(64, 48, 3.0, 2);
  const ImageF half = downsample_2x2(im);
  ASSERT_EQ(half.width(), 32);
  for (int c = 0; c < 3; ++c) {
    double a = 0, b = 0;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 64; ++x) a += double(im.at(x, y, c));
    for (int y = 0; y < 24; ++y)
      for (int x = 0; x < 32; ++x) b += double(half.at(x, y, c));
    EXPECT_NEAR(a / (64 * 48), b / (32 * 24), 1e-6);  // float block means, double sums
  }
}

TEST(SlicingBloom, EnergyAddedIsFourTimesTheBlurredHalfImage) {
  // A bright spot far from the borders: the additive composite adds 4 x the half-resolution sum.
  ImageF im(96, 80, 3, 0.1f);
  for (int y = 38; y < 44; ++y)
    for (int x = 44; x < 52; ++x)
      for (int c = 0; c < 3; ++c) im.at(x, y, c) = 0.95f;
  BloomSettings b;
  b.enabled = true;
  const ImageF out = apply_bloom(im, b);
  ImageF half = downsample_2x2(adjust_colours(im, b.adjust));
  threshold_luminance(half, b.threshold);
  const ImageF blurred = gaussian_blur(half, b.sigma);
  double added = 0, half_sum = 0, thresholded = 0;
  for (std::size_t i = 0; i < out.size(); ++i) added += double(out.values()[i]) - double(im.values()[i]);
  for (float x : blurred.values()) half_sum += double(x);
  for (float x : half.values()) thresholded += double(x);
  EXPECT_GT(half_sum, 0);
  EXPECT_NEAR(added, 4 * half_sum, 1e-4 * added);          // float sums over 7680 pixels
  EXPECT_NEAR(half_sum, thresholded, 1e-5 * thresholded);  // the blur keeps energy away from borders
}

}  // namespace
}  // namespace meltlab::render
