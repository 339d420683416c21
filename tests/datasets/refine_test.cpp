// datasets::refined: Loop subdivision (OpenMesh) and longest-edge splits to an exact budget.
// Hand-checked cases: a unit cube's six face diagonals are its longest edges, so splitting
// six edges halves exactly those and moves no surface; one Loop step of a closed mesh gives
// 4F triangles and V + E vertices and keeps the genus.

#include <meltlab/datasets/procedural.h>
#include <meltlab/datasets/refine.h>
#include <meltlab/core/error.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "mesh_checks.h"

namespace meltlab::datasets {
namespace {

using ::testing::HasSubstr;

// Volumes of meshes with vertices on a unit grid: exact up to summation rounding.
constexpr double kVolumeTolerance = 1e-12;

using test::message_of;

TEST(Refine, SplittingTheCubesDiagonalsKeepsItsShape) {
  const sim::IndexedMesh cube = cube_triangles(1.0);
  ASSERT_EQ(cube.F.size(), 12u);
  const sim::IndexedMesh r = refined(cube, 0, 24);
  EXPECT_EQ(r.F.size(), 24u);
  EXPECT_EQ(r.V.size(), 14u);  // 8 corners + 6 face centres
  const auto t = test::topology_of(r);
  EXPECT_TRUE(t.valid());
  EXPECT_EQ(t.counts.G, 0);
  EXPECT_NEAR(test::signed_volume(r), 1.0, kVolumeTolerance);
  const auto lengths = test::edge_lengths(r);
  EXPECT_NEAR(*std::max_element(lengths.begin(), lengths.end()), 1.0, 1e-15) << "every diagonal was split";
}

TEST(Refine, LoopStepsMultiplyTrianglesByFourAndKeepTopology) {
  const sim::IndexedMesh ring = torus(1.0, 0.3, 16, 8);
  const auto before = test::topology_of(ring);
  ASSERT_TRUE(before.valid());
  const sim::IndexedMesh once = refined(ring, 1, 0);
  EXPECT_EQ(once.F.size(), 4 * ring.F.size());
  EXPECT_EQ(once.V.size(), ring.V.size() + test::edge_lengths(ring).size());
  const auto after = test::topology_of(once);
  EXPECT_TRUE(after.valid());
  EXPECT_EQ(after.counts.G, 1);
  EXPECT_GT(test::signed_volume(once), 0.0);
  // Loop subdivision is an approximating scheme: the smooth limit lies inside the convex
  // polygonal torus, so the volume shrinks a little but stays close.
  EXPECT_LT(test::signed_volume(once), test::signed_volume(ring));
  EXPECT_GT(test::signed_volume(once), 0.9 * test::signed_volume(ring));
  const sim::IndexedMesh budget = refined(ring, 1, static_cast<std::int64_t>(4 * ring.F.size()) + 100);
  EXPECT_EQ(budget.F.size(), 4 * ring.F.size() + 100);
  EXPECT_TRUE(test::topology_of(budget).valid());
}

TEST(Refine, BadArgumentsAreRefused) {
  const sim::IndexedMesh cube = cube_triangles(1.0);
  EXPECT_THAT(message_of([&] { refined(cube, 0, 13); }), HasSubstr("plus an even number"));
  EXPECT_THAT(message_of([&] { refined(cube, 1, 40); }), HasSubstr("must be 0 or 48"));
  EXPECT_THAT(message_of([&] { refined(cube, -1, 0); }), HasSubstr("loop_levels"));
  EXPECT_THAT(message_of([&] { refined(cube, 0, 12 + 2 * 19); }), HasSubstr("edges"));
  sim::IndexedMesh open = cube;
  open.F.pop_back();
  EXPECT_THAT(message_of([&] { refined(open, 1, 0); }), HasSubstr("open"));
}

}  // namespace
}  // namespace meltlab::datasets
