// Seed 003's procedural CT phantom (render/volume/ct_phantom.h): Hounsfield values at known
// points of the nested ellipsoids, mirror symmetry, determinism per seed, the noise's statistics,
// dims and spacing, and the int16 VLB the generator writes.

#include <meltlab/render/volume/ct_phantom.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/vlb_file.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "test_files.h"

namespace meltlab::render {
namespace {

using Vec3 = Eigen::Vector3d;

// The source's volume: 256 x 256 x 113 at spacing (1, 1, 2): box sides L = (255, 255, 224).
const Vec3 kL(255, 255, 224);

TEST(Phantom, HounsfieldValuesAtKnownPoints) {
  // Along +y from the centre: water, bone shell, fat, air (semi-axes 0.35, 0.38, 0.40 of L_y).
  EXPECT_EQ(ct_phantom_hu(Vec3::Zero(), kL), hu::kWater);
  EXPECT_EQ(ct_phantom_hu(Vec3(0, 0.30 * 255, 0), kL), hu::kWater);
  EXPECT_EQ(ct_phantom_hu(Vec3(0, 0.365 * 255, 0), kL), hu::kBone);
  EXPECT_EQ(ct_phantom_hu(Vec3(0, 0.39 * 255, 0), kL), hu::kFat);
  EXPECT_EQ(ct_phantom_hu(Vec3(0, 0.41 * 255, 0), kL), hu::kAir);
  // Along z (semi-axes 0.45, 0.48, 0.50 of L_z): the shell reaches the slices near the ends.
  EXPECT_EQ(ct_phantom_hu(Vec3(0, 0, 0.46 * 224), kL), hu::kBone);
  EXPECT_EQ(ct_phantom_hu(Vec3(0, 0, 0.49 * 224), kL), hu::kFat);
  // The centres of the muscles and cavities, on both sides.
  for (double s : {-1.0, 1.0}) {
    EXPECT_EQ(ct_phantom_hu(Vec3(s * 0.20 * 255, 0.05 * 255, -0.05 * 224), kL), hu::kMuscle);
    EXPECT_EQ(ct_phantom_hu(Vec3(s * 0.08 * 255, -0.25 * 255, -0.10 * 224), kL), hu::kAir);
  }
  // The box corners lie outside the head.
  EXPECT_EQ(ct_phantom_hu(0.5 * kL, kL), hu::kAir);
}

TEST(Phantom, InnerStructuresLieInsideTheShellAndApart) {
  // Sample densely: every muscle or cavity sample must be enclosed by water/other inner
  // structures, i.e. no muscle or cavity value appears where the three outer layers are.
  int muscle = 0, cavity = 0;
  for (int k = -50; k <= 50; ++k)
    for (int j = -50; j <= 50; ++j)
      for (int i = -50; i <= 50; ++i) {
        const Vec3 f(i / 100.0, j / 100.0, k / 100.0);  // fraction of L from the centre
        const Vec3 p = f.cwiseProduct(kL);
        const double v = ct_phantom_hu(p, kL);
        const double rho2 = f.cwiseQuotient(Vec3(0.40, 0.35, 0.45)).squaredNorm();  // inner surface E2
        if (v == hu::kMuscle) {
          ++muscle;
          EXPECT_LT(rho2, 1.0);
        }
        if (v == hu::kAir && rho2 < 1.0) ++cavity;
      }
  EXPECT_GT(muscle, 100);
  EXPECT_GT(cavity, 10);
}

TEST(Phantom, DimsSpacingAndNoiseFreeMirrorSymmetry) {
  CtPhantomOptions o;
  o.dims = {64, 48, 29};
  o.noise_sigma_hu = 0;
  const ScalarVolume v = generate_ct_phantom(o);
  EXPECT_EQ(v.dims, o.dims);
  EXPECT_EQ(v.type, ScalarType::kInt16);
  EXPECT_EQ(v.spacing, Vec3(1, 1, 2));
  int asymmetric = 0;
  for (int k = 0; k < 29; ++k)
    for (int j = 0; j < 48; ++j)
      for (int i = 0; i < 64; ++i)
        if (v.value(i, j, k) != v.value(63 - i, j, k)) ++asymmetric;
  EXPECT_EQ(asymmetric, 0);
  // Every sample holds one of Table 1's values; all five occur.
  std::map<double, int> seen;
  for (std::int64_t n = 0; n < v.sample_count(); ++n) ++seen[v.value(n)];
  EXPECT_EQ(seen.size(), 5u);
  for (double h : {hu::kAir, hu::kFat, hu::kWater, hu::kMuscle, hu::kBone}) EXPECT_GT(seen[h], 0) << h;
  // The value at a sample equals the analytic value at its position (centre at (n - 1)/2).
  EXPECT_EQ(v.value(31, 23, 14), ct_phantom_hu(Vec3(-0.5, -0.5, 0), Vec3(63, 47, 56)));
}

TEST(Phantom, DeterministicPerSeedAndNoiseHasSigma20) {
  CtPhantomOptions o;
  o.dims = {40, 40, 20};
  const ScalarVolume a = generate_ct_phantom(o), b = generate_ct_phantom(o);
  EXPECT_EQ(a.bytes, b.bytes);
  EXPECT_EQ(scalar_content_hash(a), scalar_content_hash(b));
  o.seed = 2;
  const ScalarVolume c = generate_ct_phantom(o);
  EXPECT_NE(a.bytes, c.bytes);
  // Noise = sample - noise-free value: mean 0, sigma 20 (n = 32000 samples: the standard error of
  // the mean is 20/sqrt(32000) = 0.11 HU and of sigma about 0.08 HU; tolerances are > 5 of them,
  // plus the rounding to integers, which adds variance 1/12).
  o.seed = 1;
  o.noise_sigma_hu = 0;
  const ScalarVolume clean = generate_ct_phantom(o);
  double sum = 0, sum2 = 0;
  const auto n = double(a.sample_count());
  for (std::int64_t i = 0; i < a.sample_count(); ++i) {
    const double d = a.value(i) - clean.value(i);
    sum += d;
    sum2 += d * d;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.6);
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), std::sqrt(400.0 + 1.0 / 12.0), 0.5);
}

TEST(Phantom, FullSizeVlbAndNormalisedSceneVolume) {
  const test::TempFolder dir;
  const ScalarVolume v = generate_ct_phantom(CtPhantomOptions{});
  EXPECT_EQ(v.dims, (std::array<int, 3>{256, 256, 113}));
  write_vlb(dir.path() / "head.vlb", v);
  const VlbFile f = read_vlb(dir.path() / "head.vlb");
  EXPECT_EQ(f.header.type, ScalarType::kInt16);
  EXPECT_EQ(f.header.spacing, Vec3(1, 1, 2));
  EXPECT_EQ(f.volume.bytes, v.bytes);
  // Air with noise reaches below -1000 and bone above 1000 (the source's example: -1117 .. 2248).
  EXPECT_LT(f.header.min, -1000);
  EXPECT_GT(f.header.max, 1000);
  // The scene's generated kind: normalised to [0, 1] exactly, node samples at the spacing.
  VolumeGenerateOptions g;
  g.kind = VolumeKind::kCtPhantom;
  g.nx = 256, g.ny = 256, g.nz = 113;
  const Volume n = generate_volume(g);
  EXPECT_EQ(n.value_range(), (std::array<float, 2>{0.0f, 1.0f}));
  EXPECT_EQ(n.spacing(), Vec3(1, 1, 2));
  EXPECT_EQ(n.domain().hi, Vec3(255, 255, 224));
}

}  // namespace
}  // namespace meltlab::render
