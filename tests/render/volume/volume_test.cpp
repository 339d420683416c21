// The dense volume (render/volume/volume.h) and the seed-000 data (render/volume/generate.h):
// placement, trilinear sampling with clamp and wrap addressing, central-difference gradients on
// linear fields, quantised storage, Perlin's improved noise against its reference value, and the
// turbulence volumes' invariants.

#include <meltlab/core/error.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/volume.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace meltlab::render {
namespace {

using Vec3 = Eigen::Vector3d;

// A linear field f = 0.01 i + 0.02 j + 0.03 k on a 5 x 6 x 7 float volume.
Volume linear_field() {
  Volume v = Volume::allocate(5, 6, 7, SampleType::kFloat32);
  for (int k = 0; k < 7; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 5; ++i) v.set_value(i, j, k, 0.01 * i + 0.02 * j + 0.03 * k);
  return v;
}

TEST(Volume, PlacementOfCellCentredAndNodeSamples) {
  Volume v = Volume::allocate(4, 2, 8, SampleType::kFloat32);
  v.fit_to_box(Box3{Vec3(-2, -1, 0), Vec3(2, 1, 4)});
  EXPECT_EQ(v.spacing(), Vec3(1, 1, 0.5));
  EXPECT_EQ(v.origin(), Vec3(-1.5, -0.5, 0.25));
  EXPECT_EQ(v.domain().lo, Vec3(-2, -1, 0));
  EXPECT_EQ(v.domain().hi, Vec3(2, 1, 4));
  v.set_placement(SamplePlacement::kNodes);
  v.fit_to_box(Box3{Vec3(0, 0, 0), Vec3(3, 1, 7)});
  EXPECT_EQ(v.spacing(), Vec3(1, 1, 1));
  EXPECT_EQ(v.domain().hi, Vec3(3, 1, 7));
  EXPECT_EQ(v.world_from_index(Vec3(3, 1, 7)), Vec3(3, 1, 7));
}

TEST(Volume, TrilinearIsExactOnLinearFieldsAndClampsOrWraps) {
  Volume v = linear_field();
  v.set_placement(SamplePlacement::kNodes);
  v.fit_to_box(Box3{Vec3(0, 0, 0), Vec3(4, 5, 6)});  // unit spacing: world = index
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0, 1);
  for (int n = 0; n < 1000; ++n) {
    const Vec3 p(4 * U(rng), 5 * U(rng), 6 * U(rng));
    EXPECT_NEAR(v.sample(p), 0.01 * p.x() + 0.02 * p.y() + 0.03 * p.z(), 1e-6);  // float arithmetic
  }
  EXPECT_EQ(v.sample(Vec3(-0.1, 0, 0)), 0.0f);  // outside the domain
  // Clamp: half a sample beyond the last one reads the border sample; wrap: the first one.
  Volume c = linear_field();
  c.fit_to_box(Box3{Vec3(0, 0, 0), Vec3(5, 6, 7)});  // cell-centred, unit cells
  EXPECT_NEAR(c.sample(Vec3(4.9, 0.5, 0.5)), c.value(4, 0, 0), 1e-7);
  EXPECT_NEAR(c.sample(Vec3(4.9, 0.5, 0.5), VolumeAddress::kWrap),
              0.6 * double(c.value(4, 0, 0)) + 0.4 * double(c.value(0, 0, 0)), 1e-6);
}

TEST(Volume, CentralDifferencesAreExactOnLinearFields) {
  const Volume v = linear_field();
  for (int k = 1; k < 6; ++k)
    for (int j = 1; j < 5; ++j)
      for (int i = 1; i < 4; ++i) {
        const Vec3 g = v.gradient_index(i, j, k);
        EXPECT_NEAR(g.x(), 0.01, 1e-7);
        EXPECT_NEAR(g.y(), 0.02, 1e-7);
        EXPECT_NEAR(g.z(), 0.03, 1e-7);
      }
  // Clamp-to-edge at the border: a one-sided difference, halved.
  EXPECT_NEAR(v.gradient_index(0, 2, 2).x(), 0.005, 1e-7);
  // World gradients divide by the spacing.
  Volume w = linear_field();
  w.set_placement(SamplePlacement::kNodes);
  w.fit_to_box(Box3{Vec3(0, 0, 0), Vec3(8, 5, 6)});  // spacing 2 along x
  EXPECT_NEAR(w.gradient(Vec3(3.3, 2.2, 3.1)).x(), 0.005, 1e-7);
  EXPECT_NEAR(w.gradient(Vec3(3.3, 2.2, 3.1)).z(), 0.03, 1e-7);
}

TEST(Volume, QuantisedStorageKeepsValuesToHalfAStep) {
  VolumeGenerateOptions g;
  g.nx = g.ny = g.nz = 16;
  const Volume f = generate_volume(g);
  for (auto type : {SampleType::kUint8, SampleType::kUint16}) {
    const Volume q = f.quantised(type);
    const double step = type == SampleType::kUint8 ? 1 / 255.0 : 1 / 65535.0;
    double worst = 0;
    for (int k = 0; k < 16; ++k)
      for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 16; ++i)
          worst = std::max(worst, std::abs(double(q.value(i, j, k)) - double(f.value(i, j, k))));
    EXPECT_LE(worst, 0.5 * step * (1 + 1e-5));
    EXPECT_EQ(q.domain().hi, f.domain().hi);
  }
}

TEST(Volume, RefusesBadDimensionsAndCountsOverTheLimit) {
  EXPECT_THROW(Volume::allocate(0, 4, 4, SampleType::kFloat32), InputError);
  EXPECT_THROW(Volume::allocate(-3, 4, 4, SampleType::kUint8), InputError);
  EXPECT_THROW(Volume::allocate(1 << 30, 1 << 30, 1 << 30, SampleType::kUint8),
               InputError);  // overflows int64? no: over the limit
  Volume v = Volume::allocate(2, 2, 2, SampleType::kFloat32);
  EXPECT_THROW(v.fit_to_box(Box3{Vec3(0, 0, 0), Vec3(1, 0, 1)}), InputError);
}

TEST(ImprovedNoise, MatchesPerlinsReference) {
  // The value Perlin's Java reference implementation (2002) prints for this point.
  EXPECT_NEAR(improved_noise(3.14, 42, 7), 0.13691995878400012, 1e-15);
  // Zero at every lattice point (all gradient dot products vanish).
  for (int i = -3; i < 5; ++i) EXPECT_EQ(improved_noise(i, 2 * i, 300 - i), 0.0);
  // Nominal range [-1, 1]; period 256.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-50, 50);
  for (int n = 0; n < 20000; ++n) {
    const double x = U(rng), y = U(rng), z = U(rng);
    const double v = improved_noise(x, y, z);
    ASSERT_LE(std::abs(v), 1.0);
    EXPECT_NEAR(improved_noise(x + 256, y, z - 256), v, 1e-12);
  }
}

TEST(ImprovedNoise, TurbulenceClipsPerOctaveAndTheSum) {
  TurbulenceOptions o;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  for (int n = 0; n < 5000; ++n) {
    const double x = U(rng), y = U(rng), z = U(rng);
    const double t = turbulence(x, y, z, o);
    ASSERT_GE(t, 0.0);
    ASSERT_LE(t, 1.0);
    // By hand: Σ clip(N(4·2^k p)) / 2^k, then clipped.
    double sum = 0;
    for (int k = 0; k < 4; ++k)
      sum += std::clamp(improved_noise(4 * x * (1 << k), 4 * y * (1 << k), 4 * z * (1 << k)), 0.0, 1.0) / (1 << k);
    EXPECT_DOUBLE_EQ(t, std::clamp(sum, 0.0, 1.0));
  }
}

TEST(GeneratedVolumes, SphereVariantIsZeroOutsideAndFadesToTheRim) {
  VolumeGenerateOptions g;
  g.kind = VolumeKind::kTurbulenceSphere;
  g.nx = g.ny = g.nz = 32;
  const Volume s = generate_volume(g);
  g.kind = VolumeKind::kTurbulenceBox;
  const Volume b = generate_volume(g);
  int inside = 0;
  for (int k = 0; k < 32; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 32; ++i) {
        const Vec3 p((i + 0.5) / 32, (j + 0.5) / 32, (k + 0.5) / 32);
        const double rho = (p - Vec3::Constant(0.5)).norm() / 0.5;
        if (rho >= 1) {
          ASSERT_EQ(s.value(i, j, k), 0.0f);
        } else {
          ++inside;
          EXPECT_NEAR(s.value(i, j, k), double(b.value(i, j, k)) * (1 - rho), 1e-6);
        }
      }
  EXPECT_NEAR(inside / 32768.0, std::numbers::pi / 6, 0.01);  // the inscribed sphere's share
}

TEST(GeneratedVolumes, GenerationIsDeterministicAndHashed) {
  VolumeGenerateOptions g;
  g.nx = 20, g.ny = 16, g.nz = 12;
  const Volume a = generate_volume(g), b = generate_volume(g);
  EXPECT_EQ(volume_content_hash(a), volume_content_hash(b));
  g.noise.seed = 9;
  EXPECT_NE(volume_content_hash(generate_volume(g)), volume_content_hash(a));
  EXPECT_THROW(parse_volume_kind("smoke", "--kind"), InputError);
  EXPECT_EQ(parse_volume_kind("turbulence_sphere", "--kind"), VolumeKind::kTurbulenceSphere);
}

}  // namespace
}  // namespace meltlab::render
