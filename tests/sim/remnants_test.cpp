// The remnant check (sim/src/melt/remnants.cpp) in a workspace that lives across checks, white box:
// it reuses the connected parts while the triangles and their alive flags are unchanged, and finds
// them afresh when either changes, so every check removes exactly what a check in a fresh
// workspace removes.

#include "workspace.h"

#include "hand_meshes.h"

#include <meltlab/sim/melt.h>

#include <gtest/gtest.h>

#include <vector>

namespace meltlab::sim {
namespace {

// The pass in the long-lived workspace `ws` against remove_inverted_parts() on a copy (a fresh
// workspace): the same count, the same vertices and triangles left, and the workspace's parts
// equal to parts found afresh.
void expect_like_fresh(TriMesh<double>& m, MeltWorkspace& ws, std::int64_t expected, const char* step) {
  TriMesh<double> fresh = m;
  EXPECT_EQ(remove_inverted_parts(fresh), expected) << step;
  EXPECT_EQ(remove_inverted_parts_pass(m, ws, Execution::kSerial), expected) << step;
  EXPECT_EQ(m.vertex_alive, fresh.vertex_alive) << step;
  EXPECT_EQ(m.triangle_alive, fresh.triangle_alive) << step;
}

// Three parts (icosahedron 0-11, octahedron 12-17, octahedron 18-23). The checks: all correct (the
// parts found); the first octahedron mirrored through its centre (positions only: the parts are
// reused, the volumes are fresh, so it goes); the second octahedron glued to the icosahedron by a
// triangle that shares a corner with each (the triangles changed: the parts are found afresh, and
// the now larger part keeps its positive volume); the second octahedron inverted by swapping its
// triangles' corners and the bridge killed (alive flags changed: found afresh, it goes).
TEST(Remnants, ReusedPartsFollowTheTriangles) {
  const IndexedMesh parts = test::disjoint_union(
      test::disjoint_union(test::icosahedron(), test::translated(test::octahedron(0.5), {4, 0, 0})),
      test::translated(test::octahedron(0.5), {-4, 0, 0}));
  TriMesh<double> m = TriMesh<double>::from_indexed(parts);
  MeltWorkspace ws;
  expect_like_fresh(m, ws, 0, "all correct");
  ASSERT_EQ(ws.remnant_parts.parent[13], 12);
  ASSERT_EQ(ws.remnant_parts.parent[19], 18);

  for (std::size_t v = 12; v < 18; ++v) m.position.set(v, Vec3<double>(8, 0, 0) - m.position[v]);  // mirrored
  expect_like_fresh(m, ws, 1, "first octahedron mirrored");
  for (std::size_t v = 12; v < 18; ++v) EXPECT_FALSE(m.vertex_alive[v]);

  // A bridge (0, 11, 18): its orientation does not matter for the check, only that it joins parts.
  m.add_triangle(0, 11, 18);
  expect_like_fresh(m, ws, 0, "bridge");
  EXPECT_EQ(ws.remnant_parts.parent[19], 0) << "the bridge joins the second octahedron to the icosahedron";

  m.triangle_alive.back() = 0;
  for (std::size_t t = 0; t + 1 < m.triangle.size(); ++t)
    if (m.triangle[t][0] >= 18) std::swap(m.triangle[t][1], m.triangle[t][2]);
  expect_like_fresh(m, ws, 1, "second octahedron inverted, bridge gone");
  for (std::size_t v = 0; v < 12; ++v) EXPECT_TRUE(m.vertex_alive[v]);
  for (std::size_t v = 18; v < 24; ++v) EXPECT_FALSE(m.vertex_alive[v]);
  expect_like_fresh(m, ws, 0, "nothing left to remove");
}

}  // namespace
}  // namespace meltlab::sim
