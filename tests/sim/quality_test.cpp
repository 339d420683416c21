#include <meltlab/sim/quality.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "hand_meshes.h"
#include "vertex_sort.h"

namespace meltlab::sim {
namespace {

// Closed-form values are exact up to a few ulps of double arithmetic.
constexpr double kExact = 1e-12;

using V3 = Vec3<double>;

TEST(Quality, EquilateralTriangleIsIdeal) {
  const V3 a(0, 0, 0), b(1, 0, 0), c(0.5, std::sqrt(3.0) / 2.0, 0);
  EXPECT_NEAR(triangle_quality(a, b, c), 1.0, kExact);
  EXPECT_NEAR(triangle_twist_deg(a, b, c), 0.0, 1e-9);
}

TEST(Quality, RightIsoscelesTriangleQuality) {
  // A = 1/2, a² + b² + c² = 1 + 1 + 2 -> q = 4√3 · 0.5 / 4 = √3/2.
  EXPECT_NEAR(triangle_quality(V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0)), std::sqrt(3.0) / 2.0, kExact);
}

TEST(Quality, TwistOfRightIsoscelesTriangle) {
  // Corner at the right angle (0,0): median to (0.5,0.5) is along (1,1), the mid-line is
  // parallel to the hypotenuse (-1,1): 90°. Corner (1,0): median (-1, 0.5), mid-line
  // parallel to (0,1)-(0,0): angle acos(0.5/√1.25) = 63.435°. min alpha = 63.435° -> s = 26.565°.
  const double expected = 90.0 - std::acos(0.5 / std::sqrt(1.25)) * 180.0 / std::numbers::pi;
  EXPECT_NEAR(triangle_twist_deg(V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0)), expected, 1e-9);
}

TEST(Quality, TwistInvariantUnderSimilarityAndInRange) {
  const V3 a(0.1, 0.2, 0.3), b(1.7, -0.4, 0.2), c(0.5, 0.9, -0.8);
  const double s = triangle_twist_deg(a, b, c);
  EXPECT_GE(s, 0.0);
  EXPECT_LE(s, 90.0);
  EXPECT_NEAR(triangle_twist_deg(3.0 * a, 3.0 * b, 3.0 * c), s, 1e-9);
  EXPECT_NEAR(triangle_twist_deg(b, c, a), s, 1e-9);
}

// The twist takes one arccosine, of the largest of the three corner cosines. Against the
// definition (90° minus the smallest of the three angles, each by its own arccosine):
// arccos is monotone, so the two agree up to its rounding, < 1e-15 rad; 1e-12° leaves room
// for the conversion to degrees and the subtraction from 90°.
TEST(Quality, TwistIsNinetyMinusTheSmallestOfTheThreeCornerAngles) {
  constexpr double kTwistTol = 1e-12;
  auto definition = [](const V3& a, const V3& b, const V3& c) {
    const V3* v[3] = {&a, &b, &c};
    double min_alpha = 180.0;
    for (int i = 0; i < 3; ++i) {
      const V3 median = 0.5 * (*v[(i + 1) % 3] + *v[(i + 2) % 3]) - *v[i];
      const V3 midline = 0.5 * (*v[(i + 2) % 3] - *v[(i + 1) % 3]);
      const double cos_alpha = std::clamp(median.dot(midline) / (median.norm() * midline.norm()), -1.0, 1.0);
      min_alpha = std::min(min_alpha, std::acos(cos_alpha) * 180.0 / std::numbers::pi);
    }
    return 90.0 - min_alpha;
  };
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto point = [&] { return V3(u(rng), u(rng), u(rng)); };
  for (int i = 0; i < 3000; ++i) {
    const V3 a = point(), b = point();
    // Every third triangle is a near-sliver (c close to the line ab), where the angles are extreme.
    const V3 c = i % 3 == 0 ? a + (0.3 + 0.4 * u(rng)) * (b - a) + 1e-7 * point() : point();
    EXPECT_NEAR(triangle_twist_deg(a, b, c), definition(a, b, c), kTwistTol) << "triangle " << i;
  }
}

// The O(n) pairing sort (two stable counting passes) orders records as a stable comparison
// sort on the key does: same keys, same order of equal keys.
TEST(Quality, VertexPairSortIsAStableSortOnTheKey) {
  struct Rec {
    std::uint64_t key;
    int id;
  };
  std::mt19937_64 rng(11);
  for (std::size_t n_slots : {std::size_t{1}, std::size_t{5}, std::size_t{300}}) {
    for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{17}, std::size_t{5000}}) {
      std::uniform_int_distribution<std::uint64_t> vertex(0, n_slots - 1);
      std::vector<Rec> recs;
      for (std::size_t i = 0; i < n; ++i) recs.push_back({vertex(rng) << 32 | vertex(rng), static_cast<int>(i)});
      std::vector<Rec> expected = recs;
      std::stable_sort(expected.begin(), expected.end(), [](const Rec& a, const Rec& b) { return a.key < b.key; });
      sort_by_vertex_pair(recs, n_slots);
      ASSERT_EQ(recs.size(), expected.size());
      for (std::size_t i = 0; i < n; ++i) {
        EXPECT_EQ(recs[i].key, expected[i].key) << i;
        EXPECT_EQ(recs[i].id, expected[i].id) << i;
      }
    }
  }
}

TEST(Quality, SliverIsNearWorst) {
  const V3 a(0, 0, 0), b(1, 0, 0), c(0.5, 1e-6, 0);
  EXPECT_LT(triangle_quality(a, b, c), 1e-5);
  EXPECT_GT(triangle_twist_deg(a, b, c), 89.9);
}

TEST(Quality, UnitCubeVolumeAreaDihedral) {
  const auto q = mesh_quality(TriMesh<double>::from_indexed(test::cube12()));
  EXPECT_NEAR(q.volume, 1.0, kExact);
  EXPECT_NEAR(q.area, 6.0, kExact);
  // 12 cube edges at 90° and 6 face diagonals at 0°: Qd = 12·90/18 = 60°.
  EXPECT_EQ(q.edges, 18);
  EXPECT_NEAR(q.Qd, 60.0, 1e-9);
  EXPECT_NEAR(q.max_d, 90.0, 1e-9);
  EXPECT_NEAR(q.Qq, std::sqrt(3.0) / 2.0, kExact);
  EXPECT_EQ(q.bbox_min, V3(0, 0, 0));
  EXPECT_EQ(q.bbox_max, V3(1, 1, 1));
}

TEST(Quality, OctahedronVolumeAndDihedral) {
  const double r = 2.0;
  const auto q = mesh_quality(TriMesh<double>::from_indexed(test::octahedron(r)));
  EXPECT_NEAR(q.volume, 4.0 / 3.0 * r * r * r, kExact);
  // Angle between adjacent face normals (1,1,1)/√3 and (1,1,-1)/√3 is acos(1/3).
  EXPECT_NEAR(q.Qd, std::acos(1.0 / 3.0) * 180.0 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(q.Qq, 1.0, kExact);
  EXPECT_NEAR(mesh_volume(TriMesh<double>::from_indexed(test::octahedron(r))), q.volume, kExact);
}

}  // namespace
}  // namespace meltlab::sim
