#include <meltlab/sim/mesh.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

TEST(Mesh, LiveFlagCountIsStdCount) {
  // count_live_flags counts runs of 255 blocks of 64 flags in byte counters: every length around the
  // block and run boundaries, flags 0, 1 and other values (not counted, as std::count(…, 1) does
  // not), and all-ones runs that fill the byte counters to 255.
  std::uint32_t state = 12345;
  auto next = [&] { return state = state * 1664525u + 1013904223u; };
  const std::uint8_t values[4] = {0, 1, 2, 255};
  for (std::size_t n :
       {std::size_t(0), std::size_t(1), std::size_t(63), std::size_t(64), std::size_t(65), std::size_t(255 * 64 - 1),
        std::size_t(255 * 64), std::size_t(255 * 64 + 1), std::size_t(3 * 255 * 64 + 100), std::size_t(48000)}) {
    for (int kind = 0; kind < 3; ++kind) {
      std::vector<std::uint8_t> flags(n);
      for (auto& f : flags)
        f = kind == 0 ? 1 : kind == 1 ? values[(next() >> 16) % 4] : std::uint8_t((next() >> 16) % 2);
      const auto expected = static_cast<std::size_t>(std::count(flags.begin(), flags.end(), 1));
      EXPECT_EQ(count_live_flags(flags.data(), n), expected) << n << " flags, kind " << kind;
    }
  }
  auto m = TriMesh<double>::from_indexed(test::tetrahedron_fig_2_13());
  m.triangle_alive[2] = 0, m.vertex_alive[1] = 0;
  EXPECT_EQ(m.live_triangle_count(), 3u);
  EXPECT_EQ(m.live_vertex_count(), 3u);
}

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
