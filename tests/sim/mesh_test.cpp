#include <meltlab/sim/mesh.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

TEST(Mesh, RotateMinFirstKeepsOrientation) {
  EXPECT_EQ(rotate_min_first({3, 1, 2}), (Triangle{1, 2, 3}));
  EXPECT_EQ(rotate_min_first({2, 3, 1}), (Triangle{1, 2, 3}));
  EXPECT_EQ(rotate_min_first({1, 3, 2}), (Triangle{1, 3, 2}));  // the other orientation stays different
  EXPECT_EQ(rotate_min_first({3, 2, 1}), (Triangle{1, 3, 2}));
}

// Fig. 2.13: with A..D = 0..3 the sorted triangles are (0,3,1), (1,3,2), (0,2,3), (0,1,2)
// and Eq. 2.9 gives outward normals for all four faces.
TEST(Mesh, TetrahedronFig213SortedAndOutward) {
  const auto m = TriMesh<double>::from_indexed(test::tetrahedron_fig_2_13());
  const std::vector<Triangle> expected = {{0, 3, 1}, {1, 3, 2}, {0, 2, 3}, {0, 1, 2}};
  EXPECT_EQ(m.triangle, expected);
  Vec3<double> centroid = Vec3<double>::Zero();
  for (const auto& p : m.position) centroid += p / 4.0;
  for (const auto& t : m.triangle) {
    const auto& a = m.position[static_cast<std::size_t>(t[0])];
    const auto& b = m.position[static_cast<std::size_t>(t[1])];
    const auto& c = m.position[static_cast<std::size_t>(t[2])];
    const Vec3<double> n = (b - a).cross(c - a);
    EXPECT_GT(n.dot((a + b + c) / 3.0 - centroid), 0.0) << "face normal must point out";
  }
  const auto topo = check_topology(m);
  EXPECT_TRUE(topo.valid());
  EXPECT_EQ(topo.counts.chi, 0);
  EXPECT_EQ(topo.counts.V, 4);
  EXPECT_EQ(topo.counts.E, 6);
  EXPECT_EQ(topo.counts.F, 4);
  EXPECT_EQ(topo.counts.G, 0);
}

TEST(Mesh, ToIndexedDropsDeadSlotsAndRenumbers) {
  auto m = TriMesh<double>::from_indexed(
      test::disjoint_union(test::octahedron(), test::translated(test::octahedron(), {5, 0, 0})));
  for (std::size_t t = 0; t < 8; ++t) m.triangle_alive[t] = 0;
  for (std::size_t v = 0; v < 6; ++v) m.vertex_alive[v] = 0;
  const IndexedMesh out = m.to_indexed();
  ASSERT_EQ(out.V.size(), 6u);
  ASSERT_EQ(out.F.size(), 8u);
  EXPECT_DOUBLE_EQ(out.V[0].x(), 6.0);  // first vertex of the second octahedron
  for (const auto& t : out.F)
    for (Index v : t) EXPECT_LT(v, 6);
}

TEST(Mesh, CastKeepsTopologyAndRoundsPositions) {
  const auto md = TriMesh<double>::from_indexed(test::octahedron(0.1));
  const TriMesh<float> mf = md.cast<float>();
  EXPECT_EQ(mf.triangle, md.triangle);
  for (std::size_t v = 0; v < md.vertex_slots(); ++v)
    EXPECT_EQ(mf.position[v].x(), static_cast<float>(md.position[v].x()));
}

}  // namespace
}  // namespace meltlab::sim
