// The liquid mask (sim/liquid_mask.h): the spreading filter of Eq. 7.12 on hand-built grids,
// its 4-sample form (Eq. 7.13), the deposit pass, monotonic growth under a standing object,
// fading once the object is gone, thresholds, serial == parallel.

#include <meltlab/core/error.h>
#include <meltlab/sim/liquid_mask.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

// Sums of a few hundred floats of order 1: rounding is ~1e-7 relative per step.
constexpr double kMassTol = 1e-5;
// Eq. 7.13 re-associates the same 16 products: float rounding only.
constexpr float kBilinearTol = 1e-6f;

std::vector<float> grid(int w, int h) { return std::vector<float>(static_cast<std::size_t>(w) * h, 0.0f); }
float& at(std::vector<float>& g, int w, int i, int j) { return g[static_cast<std::size_t>(j) * w + i]; }
double sum(const std::vector<float>& g) { return std::accumulate(g.begin(), g.end(), 0.0); }

TEST(SpreadFilter, SingleTexelBecomesFourTwoByTwoBlocks) {
  const int w = 9, h = 9;
  auto g = grid(w, h), out = grid(w, h);
  at(g, w, 4, 4) = 16.0f;
  spread_mask(g, out, w, h, false);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const int di = std::abs(i - 4), dj = std::abs(j - 4);
      const float want = (di >= 1 && di <= 2 && dj >= 1 && dj <= 2) ? 1.0f : 0.0f;  // Eq. 7.12's ones, /16
      EXPECT_EQ(out[static_cast<std::size_t>(j) * w + i], want) << i << "," << j;
    }
}

TEST(SpreadFilter, ConservesMassAwayFromTheBorder) {
  const int w = 20, h = 16;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  auto g = grid(w, h), out = grid(w, h);
  for (int j = 2; j < h - 2; ++j)  // nothing within 2 texels of the border
    for (int i = 2; i < w - 2; ++i) at(g, w, i, j) = U(rng);
  spread_mask(g, out, w, h, false);
  EXPECT_NEAR(sum(out), sum(g), kMassTol * sum(g));
  // The peak is diluted: max never grows.
  EXPECT_LE(*std::max_element(out.begin(), out.end()), *std::max_element(g.begin(), g.end()));
}

TEST(SpreadFilter, LosesExactlyWhatFallsOffTheBorder) {
  const int w = 8, h = 8;
  auto g = grid(w, h), out = grid(w, h);
  // A corner texel: of its 16 targets only the 2x2 block at (+1..+2, +1..+2) is inside.
  at(g, w, 0, 0) = 16.0f;
  spread_mask(g, out, w, h, false);
  EXPECT_FLOAT_EQ(static_cast<float>(sum(out)), 4.0f);
  // An edge texel (row 0, column 4): 8 of its 16 targets are inside.
  g = grid(w, h);
  at(g, w, 4, 0) = 16.0f;
  spread_mask(g, out, w, h, false);
  EXPECT_FLOAT_EQ(static_cast<float>(sum(out)), 8.0f);
  // One texel in from the edge (row 1): rows -1 are lost (4 of 16).
  g = grid(w, h);
  at(g, w, 4, 1) = 16.0f;
  spread_mask(g, out, w, h, false);
  EXPECT_FLOAT_EQ(static_cast<float>(sum(out)), 12.0f);
}

TEST(SpreadFilter, FourBilinearSamplesEqualSixteenTaps) {
  const int w = 33, h = 21;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  auto g = grid(w, h);
  for (auto& v : g) v = U(rng);  // including the border
  std::vector<float> a, b;
  spread_mask(g, a, w, h, false);
  spread_mask_bilinear4(g, b, w, h);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_NEAR(a[k], b[k], kBilinearTol) << k;
}

TEST(SpreadFilter, SerialEqualsParallelBitwise) {
  const int w = 301, h = 257;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  auto g = grid(w, h);
  for (auto& v : g) v = U(rng) < 0.1f ? U(rng) : 0.0f;
  std::vector<float> s = g, p = g, tmp;
  for (int it = 0; it < 20; ++it) {
    spread_mask(s, tmp, w, h, false);
    s.swap(tmp);
    spread_mask(p, tmp, w, h, true);
    p.swap(tmp);
  }
  EXPECT_EQ(s, p);
}

// A unit octahedron standing on z = 0 (apex at z = 0) centred at (0, 0, 1).
TriMesh<double> standing_octahedron() {
  return TriMesh<double>::from_indexed(test::translated(test::octahedron(1.0), {0.0, 0.0, 1.0}));
}

LiquidMaskParams grid_params(int n, double side) {
  LiquidMaskParams p;
  p.width = p.height = n;
  p.texel_size = side / n;
  p.origin = Eigen::Vector2d(-0.5 * side, -0.5 * side);
  return p;
}

TEST(Deposit, FootprintIsTheSlabCrossSection) {
  // An octahedron of radius 1 on its apex: the slab z <= 0.2 (10 % of the thickness 2) is a
  // pyramid whose top cross-section is the square |x| + |y| <= 0.2 (area 0.08).
  const auto m = standing_octahedron();
  EXPECT_NEAR(deposit_slab_top(m, 0.1), 0.2, 1e-12);
  const auto p = grid_params(200, 2.0);  // h = 0.01
  const auto fp = footprint_below(m, p, 0.2);
  const double area = std::accumulate(fp.begin(), fp.end(), 0.0) * p.texel_size * p.texel_size;
  EXPECT_NEAR(area, 0.08, 0.08 * 0.1);  // discretisation of a 40-texel-wide diamond
  // A thicker slab covers more.
  const auto fp2 = footprint_below(m, p, 0.5);
  EXPECT_GT(std::accumulate(fp2.begin(), fp2.end(), 0), std::accumulate(fp.begin(), fp.end(), 0) * 4);
  // An object far off the grid draws nothing (and its texel coordinates do not overflow int).
  const auto far = TriMesh<double>::from_indexed(test::translated(test::octahedron(1.0), {1e12, -1e12, 1.0}));
  const auto fp_far = footprint_below(far, p, 0.2 + 0.0);
  EXPECT_EQ(std::accumulate(fp_far.begin(), fp_far.end(), 0), 0);
  // Nothing below the object: empty footprint.
  const auto fp0 = footprint_below(m, p, -0.1);
  EXPECT_EQ(std::accumulate(fp0.begin(), fp0.end(), 0), 0);
}

TEST(LiquidMask, GrowsMonotonicallyUnderAStandingObject) {
  // With a fixed footprint, spread (non-negative weights) and overwrite-deposit are both
  // monotone maps, and the first cycle raises the zero mask, so every texel can only grow.
  const auto m = standing_octahedron();
  auto p = grid_params(96, 6.0);
  p.far_fraction = 0.25;
  p.threshold = 0.2f;
  LiquidMask mask(p);
  std::vector<float> prev = mask.values();
  std::int64_t prev_wet = 0;
  for (int c = 0; c < 60; ++c) {
    mask.step(m, true);
    for (std::size_t k = 0; k < prev.size(); ++k)
      ASSERT_GE(mask.values()[k], prev[k]) << "cycle " << c << " texel " << k;
    EXPECT_GE(mask.wet_count(), prev_wet);
    prev = mask.values();
    prev_wet = mask.wet_count();
  }
  EXPECT_GT(mask.last_footprint_texels(), 0);
  // The puddle spread beyond the footprint.
  EXPECT_GT(mask.wet_count(), mask.last_footprint_texels());
  EXPECT_LE(mask.max_value(), 1.0f);
}

TEST(LiquidMask, FadesOnceTheObjectIsGone) {
  const auto m = standing_octahedron();
  auto p = grid_params(64, 6.0);
  p.far_fraction = 0.25;
  p.threshold = 0.05f;
  LiquidMask mask(p);
  for (int c = 0; c < 30; ++c) mask.step(m, false);
  ASSERT_TRUE(mask.any_wet());
  TriMesh<double> gone;  // an empty mesh: no deposit
  double prev_total = mask.total();
  float prev_max = mask.max_value();
  int cycles_to_dry = -1;
  for (int c = 0; c < 2000; ++c) {
    mask.step(gone, false);
    EXPECT_EQ(mask.last_footprint_texels(), 0);
    EXPECT_LE(mask.total(), prev_total * (1 + 1e-6));
    EXPECT_LE(mask.max_value(), prev_max);
    prev_total = mask.total();
    prev_max = mask.max_value();
    if (!mask.any_wet()) {
      cycles_to_dry = c;
      break;
    }
  }
  EXPECT_GT(cycles_to_dry, 0) << "the puddle never dried";
}

TEST(LiquidMask, ThresholdTextureDecidesPresence) {
  auto p = grid_params(16, 1.0);
  p.threshold = 0.5f;
  LiquidMask mask(p);
  mask.values()[static_cast<std::size_t>(3 * 16 + 3)] = 0.3f;
  EXPECT_FALSE(mask.wet(3, 3));
  std::vector<float> tp(256, 0.5f);
  tp[3 * 16 + 3] = 0.25f;  // a low spot floods first
  mask.set_threshold_texture(tp);
  EXPECT_TRUE(mask.wet(3, 3));
  EXPECT_EQ(mask.wet_count(), 1);
  EXPECT_THROW(mask.set_threshold_texture(std::vector<float>(10, 0.5f)), InputError);
}

TEST(LiquidMask, AddBlendAccumulatesAndBadParamsAreRefused) {
  const auto m = standing_octahedron();
  auto p = grid_params(64, 6.0);
  p.blend = DepositBlend::kAdd;
  LiquidMask mask(p);
  for (int c = 0; c < 5; ++c) mask.step(m, false);
  EXPECT_GT(mask.max_value(), 1.0f);
  auto bad = p;
  bad.far_fraction = 0.0;
  EXPECT_THROW(LiquidMask{bad}, InputError);
  bad = p;
  bad.width = 2;
  EXPECT_THROW(LiquidMask{bad}, InputError);
}

}  // namespace
}  // namespace meltlab::sim
