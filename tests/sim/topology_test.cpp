#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

using Kind = TopologyProblem::Kind;

bool has_problem(const TopologyReport& r, Kind k) {
  for (const auto& p : r.problems)
    if (p.kind == k) return true;
  return false;
}

TEST(Topology, ClosedMeshesAreValidWithChiZero) {
  for (const auto& m : {test::tetrahedron_fig_2_13(), test::octahedron(), test::cube12()}) {
    const auto r = check_topology(TriMesh<double>::from_indexed(m));
    EXPECT_TRUE(r.valid());
    EXPECT_EQ(r.counts.chi, 0);
    EXPECT_EQ(r.counts.S, 1);
    EXPECT_EQ(r.counts.G, 0);
    EXPECT_EQ(2 * r.counts.E, 3 * r.counts.F) << "closed triangle mesh: every edge on two faces";
  }
}

TEST(Topology, CubeOfQuadsCountsAsPolygons) {
  PolygonMesh cube;
  for (int k = 0; k < 8; ++k) cube.V.push_back(Vec3<double>(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  cube.faces = {{{0, 2, 3, 1}, {}}, {{4, 5, 7, 6}, {}}, {{0, 1, 5, 4}, {}},
                {{2, 6, 7, 3}, {}}, {{0, 4, 6, 2}, {}}, {{1, 3, 7, 5}, {}}};
  const auto r = check_topology(cube);
  EXPECT_TRUE(r.valid());
  EXPECT_EQ(r.counts.V, 8);
  EXPECT_EQ(r.counts.E, 12);
  EXPECT_EQ(r.counts.F, 6);
  EXPECT_EQ(r.counts.chi, 0);
}

TEST(Topology, TwoPartsCountTwoShells) {
  const auto m = test::disjoint_union(test::cube12(), test::translated(test::cube12(), {3, 0, 0}));
  const auto r = check_topology(TriMesh<double>::from_indexed(m));
  EXPECT_TRUE(r.valid());
  EXPECT_EQ(r.counts.S, 2);
  EXPECT_EQ(r.counts.V, 16);
  EXPECT_EQ(r.counts.chi, 0);
}

// euler_counts() (MeshStatistics, the per-cycle statistics of `meltlab simulate`) skips the vertex-fan and
// orphan checks but must count exactly as the full check: valid meshes, two shells, an open
// mesh, two tetrahedra sharing one vertex (a non-manifold vertex), a degenerate face and dead
// triangles.
TEST(Topology, EulerCountsAreTheFullChecksCounts) {
  std::vector<TriMesh<double>> meshes;
  for (const auto& m : {test::tetrahedron_fig_2_13(), test::octahedron(), test::cube12(), test::icosahedron()})
    meshes.push_back(TriMesh<double>::from_indexed(m));
  meshes.push_back(TriMesh<double>::from_indexed(
      test::disjoint_union(test::cube12(), test::translated(test::icosahedron(), {3, 0, 0}))));
  auto open = test::octahedron();
  open.F.pop_back();
  meshes.push_back(TriMesh<double>::from_indexed(open));
  auto pinched = test::disjoint_union(test::tetrahedron_fig_2_13(), test::tetrahedron_fig_2_13());
  for (auto& f : pinched.F)
    for (auto& v : f)
      if (v == 4) v = 0;  // the second tetrahedron's first vertex is the first one's
  meshes.push_back(TriMesh<double>::from_indexed(pinched));
  auto degenerate = test::cube12();
  degenerate.F.push_back({0, 0, 1});
  meshes.push_back(TriMesh<double>::from_indexed(degenerate));
  TriMesh<double> dead = TriMesh<double>::from_indexed(test::icosahedron());
  dead.triangle_alive[3] = 0;
  dead.triangle_alive[7] = 0;
  meshes.push_back(dead);
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const EulerCounts full = check_topology(meshes[i]).counts, fast = euler_counts(meshes[i]);
    EXPECT_EQ(fast.V, full.V) << "mesh " << i;
    EXPECT_EQ(fast.E, full.E) << "mesh " << i;
    EXPECT_EQ(fast.F, full.F) << "mesh " << i;
    EXPECT_EQ(fast.H, full.H) << "mesh " << i;
    EXPECT_EQ(fast.S, full.S) << "mesh " << i;
    EXPECT_EQ(fast.G, full.G) << "mesh " << i;
    EXPECT_EQ(fast.chi, full.chi) << "mesh " << i;
    EXPECT_EQ(fast.genus_valid, full.genus_valid) << "mesh " << i;
  }
  EXPECT_EQ(euler_counts(meshes[4]).S, 2);
  EXPECT_FALSE(check_topology(meshes[6]).manifold) << "the pinched pair is the case the fan check exists for";
}

TEST(Topology, OpenMeshReportsBoundaryEdge) {
  auto m = test::octahedron();
  m.F.pop_back();
  const auto r = check_topology(TriMesh<double>::from_indexed(m));
  EXPECT_FALSE(r.valid());
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.boundary_edges, 3);
  ASSERT_TRUE(has_problem(r, Kind::kBoundaryEdge));
  EXPECT_NE(r.problems.front().describe().find("boundary edge"), std::string::npos);
}

TEST(Topology, FlippedFaceReportsInconsistentOrientation) {
  auto m = test::octahedron();
  std::swap(m.F[0][1], m.F[0][2]);
  const auto r = check_topology(TriMesh<double>::from_indexed(m));
  EXPECT_FALSE(r.oriented);
  EXPECT_EQ(r.misoriented_edges, 3);
  EXPECT_FALSE(r.valid());
}

TEST(Topology, ThreeFacesOnAnEdgeIsNonManifold) {
  // Octahedron plus a fin: an extra closed tetrahedron glued along edge (0, 2).
  auto m = test::octahedron();
  m.V.push_back({0.5, 0.5, -2.0});  // v6
  m.V.push_back({0.6, 0.6, -3.0});  // v7
  m.F.push_back({0, 6, 2});
  m.F.push_back({2, 6, 7});
  m.F.push_back({0, 7, 6});
  m.F.push_back({0, 2, 7});
  const auto r = check_topology(TriMesh<double>::from_indexed(m));
  EXPECT_FALSE(r.manifold);
  EXPECT_GE(r.nonmanifold_edges, 1);
  ASSERT_TRUE(has_problem(r, Kind::kNonManifoldEdge));
  for (const auto& p : r.problems)
    if (p.kind == Kind::kNonManifoldEdge) {
      EXPECT_EQ(p.a, 0);
      EXPECT_EQ(p.b, 2);
      EXPECT_EQ(p.count, 4);
    }
}

TEST(Topology, TwoSolidsTouchingAtAVertexIsNonManifoldVertex) {
  // Second octahedron shares vertex 0 (+x) of the first: translate by (2,0,0) and weld its -x to it.
  auto a = test::octahedron();
  auto b = test::translated(test::octahedron(), {2, 0, 0});
  auto m = test::disjoint_union(a, b);
  for (auto& t : m.F)
    for (auto& v : t)
      if (v == 6 + 1) v = 0;  // b's -x vertex (index 7) is a's +x vertex
  const auto r = check_topology(TriMesh<double>::from_indexed(m));
  EXPECT_FALSE(r.manifold);
  EXPECT_EQ(r.nonmanifold_vertices, 1);
  ASSERT_TRUE(has_problem(r, Kind::kNonManifoldVertex));
  EXPECT_EQ(r.problems.front().a, 0);
  EXPECT_EQ(r.problems.front().count, 2);
}

TEST(Topology, OrphanAndDeadReferencesAreReported) {
  auto m = TriMesh<double>::from_indexed(test::octahedron());
  m.add_vertex({9, 9, 9});
  auto r = check_topology(m);
  EXPECT_EQ(r.orphan_vertices, 1);
  EXPECT_FALSE(r.valid());
  auto m2 = TriMesh<double>::from_indexed(test::octahedron());
  m2.vertex_alive[3] = 0;
  r = check_topology(m2);
  EXPECT_EQ(r.dead_vertex_references, 1);
  EXPECT_FALSE(r.valid());
}

TEST(Topology, ComponentsOfLiveTriangles) {
  const auto m = TriMesh<double>::from_indexed(
      test::disjoint_union(test::tetrahedron_fig_2_13(), test::translated(test::octahedron(), {9, 0, 0})));
  const auto [id, count] = vertex_components(m);
  EXPECT_EQ(count, 2);
  EXPECT_EQ(id[0], id[3]);
  EXPECT_NE(id[0], id[4]);
}

}  // namespace
}  // namespace meltlab::sim
