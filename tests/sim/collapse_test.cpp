#include <meltlab/core/error.h>
#include <meltlab/sim/melt.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

using V3 = Vec3<double>;
constexpr double kExact = 1e-12;

// Fig. 3.11 (1-based in the monograph): chains 8->6->3, 9->6->3, 12->9->6->3 resolve to 3.
TEST(Collapse, ChainFlatteningFig311) {
  const std::vector<Index> before_1based = {1, 2, 3, 4, 5, 3, 7, 6, 6, 10, 3, 9};
  const std::vector<Index> after_1based = {1, 2, 3, 4, 5, 3, 7, 3, 3, 10, 3, 3};
  std::vector<Index> before;
  for (Index i : before_1based) before.push_back(i - 1);
  const auto after = flatten_merge_targets(before);
  for (std::size_t k = 0; k < after.size(); ++k) EXPECT_EQ(after[k] + 1, after_1based[k]) << "index " << k + 1;
  EXPECT_THROW(flatten_merge_targets({0, 2, 2}), InvariantError) << "targets must not exceed the index";
}

// One short edge (0, 2): vertex 2 is removed, vertex 0 moves to the midpoint, the two
// triangles on the edge are deleted and the octahedron becomes a valid bipyramid.
TEST(Collapse, ShortEdgeCollapsesToItsMidpoint) {
  auto mesh = test::octahedron(1.0);
  mesh.V[2] = V3(0.9, 0.1, 0.0);
  auto m = TriMesh<double>::from_indexed(mesh);
  const auto r = collapse_short_edges(m, 0.5, MergeMode::kClusterMean);
  EXPECT_EQ(r.merged_vertices, 1);
  EXPECT_EQ(r.degenerate_triangles, 2);
  EXPECT_FALSE(m.vertex_alive[2]);
  EXPECT_NEAR((m.position[0] - V3(0.95, 0.05, 0.0)).norm(), 0.0, kExact);
  EXPECT_EQ(m.reindex[2], 0);
  const auto topo = check_topology(m);
  EXPECT_TRUE(topo.valid());
  EXPECT_EQ(topo.counts.V, 5);
  EXPECT_EQ(topo.counts.F, 6);
}

TEST(Collapse, NothingShortNothingChanges) {
  auto m = TriMesh<double>::from_indexed(test::icosahedron());
  const auto before = m.triangle;
  const auto r = collapse_short_edges(m, 0.1, MergeMode::kClusterMean);
  EXPECT_EQ(r.merged_vertices, 0);
  EXPECT_EQ(m.triangle, before);
}

// Icosahedron: vertex 0's neighbours 1 and 11 are not adjacent to each other; both are
// pulled next to vertex 0, so the cluster {0, 1, 11} merges into 0.
TEST(Collapse, ClusterMeanVersusSequentialPairwise) {
  auto mesh = test::icosahedron();
  const V3 p0 = mesh.V[0];
  mesh.V[11] = p0 + V3(0.05, 0.0, 0.02);
  mesh.V[1] = p0 + V3(-0.03, 0.04, 0.0);
  const double kr = 0.2;  // icosahedron edges are 2 long
  auto mean = TriMesh<double>::from_indexed(mesh);
  collapse_short_edges(mean, kr, MergeMode::kClusterMean);
  EXPECT_NEAR((mean.position[0] - (mesh.V[0] + mesh.V[1] + mesh.V[11]) / 3.0).norm(), 0.0, kExact);
  auto pairwise = TriMesh<double>::from_indexed(mesh);
  collapse_short_edges(pairwise, kr, MergeMode::kSequentialPairwise);
  // Alg. 2's CPU loop, ascending: P0 = (P1 + P0)/2, then P0 = (P11 + P0)/2.
  const V3 expected = (mesh.V[11] + (mesh.V[1] + mesh.V[0]) / 2.0) / 2.0;
  EXPECT_NEAR((pairwise.position[0] - expected).norm(), 0.0, kExact);
  EXPECT_FALSE(mean.vertex_alive[1]);
  EXPECT_FALSE(mean.vertex_alive[11]);
}

std::set<Triangle> live_triangles(const TriMesh<double>& m) {
  std::set<Triangle> s;
  for (std::size_t t = 0; t < m.triangle_slots(); ++t)
    if (m.triangle_alive[t]) s.insert(m.triangle[t]);
  return s;
}

// The formulation is order-independent: permuting the triangle array (the order in which
// triangles mark their short edges) gives bitwise the same positions and triangles.
TEST(Collapse, IndependentOfTriangleOrder) {
  std::mt19937 rng(3);
  std::normal_distribution<double> jitter(0.0, 0.4);
  int cases_with_merges = 0;
  for (int trial = 0; trial < 50; ++trial) {
    auto mesh = test::icosahedron();
    for (auto& p : mesh.V) p += V3(jitter(rng), jitter(rng), jitter(rng));
    auto a = TriMesh<double>::from_indexed(mesh);
    std::shuffle(mesh.F.begin(), mesh.F.end(), rng);
    auto b = TriMesh<double>::from_indexed(mesh);
    const auto ra = collapse_short_edges(a, 1.2, MergeMode::kClusterMean);
    const auto rb = collapse_short_edges(b, 1.2, MergeMode::kClusterMean);
    EXPECT_EQ(ra.merged_vertices, rb.merged_vertices);
    EXPECT_EQ(a.position, b.position) << "trial " << trial;
    EXPECT_EQ(a.vertex_alive, b.vertex_alive);
    EXPECT_EQ(live_triangles(a), live_triangles(b));
    cases_with_merges += ra.merged_vertices > 0 ? 1 : 0;
  }
  EXPECT_GT(cases_with_merges, 10) << "the test must exercise merges";
}

TEST(Collapse, SerialAndParallelMarkIdentically) {
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(0.0, 0.4);
  for (int trial = 0; trial < 20; ++trial) {
    auto mesh = test::icosahedron();
    for (auto& p : mesh.V) p += V3(jitter(rng), jitter(rng), jitter(rng));
    auto a = TriMesh<double>::from_indexed(mesh);
    auto b = a;
    collapse_short_edges(a, 1.2, MergeMode::kClusterMean, Execution::kSerial);
    collapse_short_edges(b, 1.2, MergeMode::kClusterMean, Execution::kParallel);
    EXPECT_EQ(a.position, b.position);
    EXPECT_EQ(a.triangle, b.triangle);
    EXPECT_EQ(a.triangle_alive, b.triangle_alive);
  }
}

}  // namespace
}  // namespace meltlab::sim
