#include <meltlab/sim/melt.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

using V3 = Vec3<double>;

// Fig. 3.7's pinch: a valence-3 bump N on face (0,2,4) of an octahedron, and the edge
// (0,2) made short. Collapsing it turns (2,4,N) and (4,0,N) into (0,4,N) and (4,0,N): a
// glued pair whose apex N is left with two triangles. Alg. 3 removes the pair and N; the
// rest is a valid triangular bipyramid.
TEST(Glued, ConstructedPinchProducesGluedPairThatIsRemoved) {
  auto mesh = test::octahedron(1.0);
  mesh.V.push_back(V3(0.4, 0.4, 0.4));  // N = v6
  mesh.F[0] = {0, 2, 6};
  mesh.F.push_back({2, 4, 6});
  mesh.F.push_back({4, 0, 6});
  ASSERT_TRUE(check_topology(TriMesh<double>::from_indexed(mesh)).valid());
  mesh.V[2] = V3(0.9, 0.1, 0.0);
  auto m = TriMesh<double>::from_indexed(mesh);
  const auto c = collapse_short_edges(m, 0.3, MergeMode::kClusterMean);
  EXPECT_EQ(c.merged_vertices, 1);
  const auto before = check_topology(m);
  EXPECT_FALSE(before.valid()) << "the collapse leaves a glued pair";
  const auto g = remove_glued_and_sort(m);
  EXPECT_EQ(g.glued_triangles, 2);
  EXPECT_EQ(g.glued_vertices, 1);
  EXPECT_FALSE(m.vertex_alive[6]);
  const auto after = check_topology(m);
  EXPECT_TRUE(after.valid());
  EXPECT_EQ(after.counts.V, 5);
  EXPECT_EQ(after.counts.F, 6);
  EXPECT_EQ(after.counts.chi, 0);
  for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
    if (m.triangle_alive[t]) {
      EXPECT_EQ(m.triangle[t], rotate_min_first(m.triangle[t])) << "sorted min-first";
    }
  }
}

// Two solids touching at one vertex: the repair splits the pinch into one vertex per fan,
// which is how a neck that collapsed to a point separates the object into two parts.
TEST(Repair, PinchVertexIsSplitIntoParts) {
  auto mesh = test::disjoint_union(test::octahedron(), test::translated(test::octahedron(), {2, 0, 0}));
  for (auto& t : mesh.F)
    for (auto& v : t)
      if (v == 7) v = 0;  // the second octahedron's -x vertex is the first one's +x vertex
  auto m = TriMesh<double>::from_indexed(mesh);
  m.vertex_alive[7] = 0;
  ASSERT_EQ(check_topology(m).nonmanifold_vertices, 1);
  const auto r = repair_topology(m, {0});
  EXPECT_EQ(r.repair_vertex_splits, 1);
  const auto topo = check_topology(m);
  EXPECT_TRUE(topo.valid());
  EXPECT_EQ(topo.counts.S, 2);
  EXPECT_EQ(topo.counts.V, 12);
  EXPECT_EQ(topo.counts.chi, 0);
}

// An edge with four triangles (a tetrahedral fin on the octahedron's edge (0,2)) is
// collapsed; the fin then degenerates into a glued pair that is removed.
TEST(Repair, NonManifoldEdgeIsCollapsed) {
  auto mesh = test::octahedron();
  mesh.V.push_back({0.5, 0.5, -2.0});  // v6
  mesh.V.push_back({0.6, 0.6, -3.0});  // v7
  mesh.F.push_back({0, 6, 2});
  mesh.F.push_back({2, 6, 7});
  mesh.F.push_back({0, 7, 6});
  mesh.F.push_back({0, 2, 7});
  auto m = TriMesh<double>::from_indexed(mesh);
  ASSERT_EQ(check_topology(m).nonmanifold_edges, 1);
  const auto r = repair_topology(m, {0, 2});
  EXPECT_GE(r.repair_edge_collapses, 1);
  const auto topo = check_topology(m);
  EXPECT_TRUE(topo.valid()) << (topo.problems.empty() ? "" : topo.problems.front().describe());
  EXPECT_EQ(topo.counts.S, 1);
}

// A glued pair lying on top of a face: no vertex has exactly two triangles, so Alg. 3's
// count test cannot see it; the repair's link test does.
TEST(Repair, GluedPairMissedByTheCountTest) {
  auto mesh = test::octahedron();
  mesh.F.push_back({0, 4, 2});
  mesh.F.push_back({0, 2, 4});
  auto m = TriMesh<double>::from_indexed(mesh);
  const auto g = remove_glued_and_sort(m);
  EXPECT_EQ(g.glued_triangles, 0);
  const auto r = repair_topology(m, {0, 2, 4});
  EXPECT_EQ(r.repair_glued_pairs, 1);
  const auto topo = check_topology(m);
  EXPECT_TRUE(topo.valid());
  EXPECT_EQ(topo.counts.F, 8);
}

// An inside-out part (volume < 0) is removed; a correct part next to it is kept intact.
TEST(Remnants, InvertedPartIsRemoved) {
  auto inverted = test::translated(test::octahedron(0.5), {4, 0, 0});
  for (auto& t : inverted.F) std::swap(t[1], t[2]);
  auto m = TriMesh<double>::from_indexed(test::disjoint_union(test::icosahedron(), inverted));
  const auto before = m.position;
  EXPECT_EQ(remove_inverted_parts(m), 1);
  for (std::size_t v = 0; v < 12; ++v) EXPECT_TRUE(m.vertex_alive[v]);
  for (std::size_t v = 12; v < 18; ++v) EXPECT_FALSE(m.vertex_alive[v]);
  const auto topo = check_topology(m);
  EXPECT_TRUE(topo.valid());
  EXPECT_EQ(topo.counts.S, 1);
  EXPECT_EQ(m.position, before);
  EXPECT_EQ(remove_inverted_parts(m), 0) << "nothing left to remove";
}

// The parts' vertices interleaved in index order (a fixed shuffle), so that union-find joins
// parts found from both ends and each part's root (its smallest index) lies anywhere: only
// the inverted part goes, in float and double, and its vertices are exactly those removed.
TEST(Remnants, InvertedPartAmongInterleavedPartsIsRemoved) {
  auto inverted = test::translated(test::octahedron(0.5), {4, 0, 0});
  for (auto& t : inverted.F) std::swap(t[1], t[2]);
  const IndexedMesh parts = test::disjoint_union(test::disjoint_union(test::icosahedron(), inverted),
                                                 test::translated(test::icosahedron(), {-4, 0, 0}));
  const std::size_t n = parts.V.size();  // 12 + 6 + 12
  std::vector<Index> new_index(n);
  for (std::size_t v = 0; v < n; ++v) new_index[v] = static_cast<Index>((v * 7 + 3) % n);  // 7 is prime to 30
  const IndexedMesh shuffled = test::renumbered(parts, new_index);
  auto check = [&](auto m) {
    EXPECT_EQ(remove_inverted_parts(m), 1);
    for (std::size_t v = 0; v < n; ++v)
      EXPECT_EQ(m.vertex_alive[static_cast<std::size_t>(new_index[v])] != 0, v < 12 || v >= 18) << "vertex " << v;
    const auto topo = check_topology(m);
    EXPECT_TRUE(topo.valid());
    EXPECT_EQ(topo.counts.S, 2);
  };
  check(TriMesh<double>::from_indexed(shuffled));
  check(TriMesh<float>::from_indexed(shuffled));
}

// Compaction drops dead slots, keeps the live mesh and the relative order of indices (so
// every triangle stays min-index first and Alg. 2's comparisons are unchanged).
TEST(Compact, KeepsLiveMeshAndIndexOrder) {
  auto m = TriMesh<double>::from_indexed(
      test::disjoint_union(test::octahedron(), test::translated(test::icosahedron(), {5, 0, 0})));
  for (std::size_t t = 0; t < 8; ++t) m.triangle_alive[t] = 0;  // the octahedron melted away
  for (std::size_t v = 0; v < 6; ++v) m.vertex_alive[v] = 0;
  const IndexedMesh before = m.to_indexed();
  const auto new_index = compact_mesh(m);
  EXPECT_EQ(m.vertex_slots(), 12u);
  EXPECT_EQ(m.triangle_slots(), 20u);
  EXPECT_EQ(new_index[0], -1);
  EXPECT_EQ(new_index[6], 0);
  EXPECT_EQ(new_index[17], 11);
  const IndexedMesh after = m.to_indexed();
  EXPECT_EQ(after.V, before.V);
  EXPECT_EQ(after.F, before.F);
  for (const auto& t : m.triangle) EXPECT_EQ(t, rotate_min_first(t));
  for (std::size_t v = 0; v < m.vertex_slots(); ++v) EXPECT_EQ(m.reindex[v], static_cast<Index>(v));
  EXPECT_TRUE(check_topology(m).valid());
}

TEST(Repair, ValidMeshIsLeftAlone) {
  auto m = TriMesh<double>::from_indexed(test::icosahedron());
  const auto before = m.triangle;
  std::vector<Index> all(12);
  for (Index v = 0; v < 12; ++v) all[static_cast<std::size_t>(v)] = v;
  const auto r = repair_topology(m, all);
  EXPECT_FALSE(r.topology_changed());
  EXPECT_EQ(m.triangle, before);
}

}  // namespace
}  // namespace meltlab::sim
