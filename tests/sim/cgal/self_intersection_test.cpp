// The CGAL-backed self-intersection validator: known answers, slot indices through dead
// slots, broken (non-manifold) input, and the cost on a stress-test-sized mesh.

#include <meltlab/sim/cgal/self_intersection.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/polygon_mesh.h>

// CGAL's exact-constructions kernel, used here as an independent referee of the pairs.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Intersections_3/Triangle_3_Triangle_3.h>
#pragma GCC diagnostic pop

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <set>

#include "cgal_test_meshes.h"

namespace meltlab::sim {
namespace {

using test::V3;

// Two unit cubes, the second moved by this much along every axis: they interpenetrate.
const V3 kOverlapShift(0.5, 0.5, 0.5);
// Where the top vertex of the unit sphere is moved: through the bottom, slightly off-axis.
const V3 kPushedThrough(0.01, 0.02, -1.5);
// A stress-test mesh: the icosphere at this level has 20·4^6 = 81,920 triangles.
constexpr int kStressSphereLevel = 6;
// Radial noise amplitude of the stress sphere, as a fraction of the radius (small enough
// that no triangle folds over a neighbour at this resolution).
constexpr double kStressNoise = 1e-3;

template <class Real>
bool really_intersect(const TriMesh<Real>& m, Index i, Index j) {
  using K = CGAL::Exact_predicates_exact_constructions_kernel;
  auto tri = [&](Index t) {
    const Triangle& c = m.triangle[static_cast<std::size_t>(t)];
    auto p = [&](int k) {
      const Vec3<Real>& q = m.position[static_cast<std::size_t>(c[static_cast<std::size_t>(k)])];
      return K::Point_3(static_cast<double>(q.x()), static_cast<double>(q.y()), static_cast<double>(q.z()));
    };
    return K::Triangle_3(p(0), p(1), p(2));
  };
  return CGAL::do_intersect(tri(i), tri(j));
}

IndexedMesh overlapping_cubes() {
  return test::disjoint_union(test::cube12(), test::translated(test::cube12(), kOverlapShift));
}

TEST(SelfIntersections, DisjointTetrahedraDoNotIntersect) {
  const IndexedMesh two =
      test::disjoint_union(test::tetrahedron_fig_2_13(), test::translated(test::tetrahedron_fig_2_13(), V3(3, 0, 0)));
  const auto r = self_intersections(TriMesh<double>::from_indexed(two));
  EXPECT_FALSE(r.intersects);
  EXPECT_EQ(r.pairs, 0u);
  EXPECT_TRUE(r.sample.empty());
}

TEST(SelfIntersections, ClosedConvexMeshesDoNotIntersect) {
  // Neighbours share edges and vertices; none of that counts.
  for (const auto& m : {test::cube12(), test::octahedron(), test::icosahedron(), test::icosphere(3)})
    EXPECT_FALSE(self_intersections(TriMesh<double>::from_indexed(m)).intersects);
}

TEST(SelfIntersections, InterpenetratingCubesReportRealCrossPairs) {
  const TriMesh<double> m = TriMesh<double>::from_indexed(overlapping_cubes());
  const auto r = self_intersections(m);
  ASSERT_TRUE(r.intersects);
  EXPECT_EQ(r.pairs, r.sample.size());
  const Index first_of_second_cube = 12;
  for (const auto& [i, j] : r.sample) {
    EXPECT_LT(i, first_of_second_cube) << "a pair inside one convex cube cannot intersect";
    EXPECT_GE(j, first_of_second_cube);
    EXPECT_TRUE(really_intersect(m, i, j)) << "pair (" << i << ", " << j << ")";
  }
  // Each cube's corner inside the other pierces the three faces around it: at least the
  // 2 x 3 faces there meet triangles of the other cube.
  EXPECT_GE(r.pairs, 6u);
}

TEST(SelfIntersections, SphereWithAVertexPushedThroughIntersects) {
  IndexedMesh sphere = test::icosphere(2);
  ASSERT_FALSE(self_intersections(TriMesh<double>::from_indexed(sphere)).intersects);
  const auto top =
      std::max_element(sphere.V.begin(), sphere.V.end(), [](const V3& a, const V3& b) { return a.z() < b.z(); });
  *top = kPushedThrough;
  const TriMesh<double> m = TriMesh<double>::from_indexed(sphere);
  const auto r = self_intersections(m);
  ASSERT_TRUE(r.intersects);
  for (const auto& [i, j] : r.sample) EXPECT_TRUE(really_intersect(m, i, j));
}

// The overlapping cubes with dead slots everywhere: a dead vertex at a NaN position first,
// a dead triangle (that would cut both cubes) before every live one.
TriMesh<double> overlapping_cubes_with_dead_slots() {
  const IndexedMesh compact = overlapping_cubes();
  TriMesh<double> m;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  m.add_vertex(V3(nan, nan, nan));
  m.vertex_alive[0] = 0;
  for (const auto& p : compact.V) m.add_vertex(p);
  const Index cutter_a = m.add_vertex(V3(-1, 0.6, 0.7)), cutter_b = m.add_vertex(V3(3, 0.7, 0.6)),
              cutter_c = m.add_vertex(V3(0.7, 3, 0.8));
  for (const auto& t : compact.F) {
    const Index dead = m.add_triangle(cutter_a, cutter_b, cutter_c);
    m.triangle_alive[static_cast<std::size_t>(dead)] = 0;
    m.add_triangle(t[0] + 1, t[1] + 1, t[2] + 1);
  }
  return m;
}

TEST(SelfIntersections, ReportsTriangleSlotIndicesPastDeadSlots) {
  const TriMesh<double> m = overlapping_cubes_with_dead_slots();
  const auto compact = self_intersections(TriMesh<double>::from_indexed(overlapping_cubes()));
  const auto r = self_intersections(m);
  ASSERT_TRUE(r.intersects);
  EXPECT_EQ(r.pairs, compact.pairs) << "dead slots must not add or hide pairs";
  // Live triangle k of the compact mesh sits in slot 2k + 1.
  std::set<std::pair<Index, Index>> expected;
  for (const auto& [i, j] : compact.sample) expected.emplace(2 * i + 1, 2 * j + 1);
  const std::set<std::pair<Index, Index>> reported(r.sample.begin(), r.sample.end());
  EXPECT_EQ(reported, expected);
  for (const auto& [i, j] : r.sample) {
    EXPECT_TRUE(m.triangle_alive[static_cast<std::size_t>(i)] && m.triangle_alive[static_cast<std::size_t>(j)]);
    EXPECT_TRUE(really_intersect(m, i, j));
  }
}

TEST(SelfIntersections, FloatMeshGivesTheSamePairs) {
  const TriMesh<double> m = overlapping_cubes_with_dead_slots();
  const auto rd = self_intersections(m);
  const auto rf = self_intersections(m.cast<float>());  // the cube corners are exact in float
  EXPECT_EQ(rf.sample, rd.sample);
}

TEST(SelfIntersections, StopsAtMaxPairs) {
  const TriMesh<double> m = TriMesh<double>::from_indexed(overlapping_cubes());
  const auto r3 = self_intersections(m, 3);
  EXPECT_TRUE(r3.intersects);
  EXPECT_EQ(r3.pairs, 3u);
  EXPECT_EQ(r3.sample.size(), 3u);
  const auto r0 = self_intersections(m, 0);
  EXPECT_TRUE(r0.intersects) << "max_pairs = 0 still answers the yes/no question";
  EXPECT_EQ(r0.pairs, 1u);
}

TEST(SelfIntersections, SharedEdgeCountsOnlyWhenFolded) {
  TriMesh<double> m;
  m.add_vertex(V3(0, 0, 0));
  m.add_vertex(V3(1, 0, 0));
  m.add_vertex(V3(0.5, 1, 0));
  m.add_vertex(V3(0.5, -1, 0));   // 3: across the shared edge, same plane (flat)
  m.add_vertex(V3(0.5, 0.5, 0));  // 4: same side as 2, same plane (folded onto 012)
  m.add_vertex(V3(0.5, 1, 1));    // 5: same side, out of plane (a dihedral, no overlap)
  m.add_triangle(0, 1, 2);
  m.add_triangle(1, 0, 3);
  EXPECT_FALSE(self_intersections(m).intersects) << "flat neighbours";
  m.triangle_alive[1] = 0;
  m.add_triangle(1, 0, 5);
  EXPECT_FALSE(self_intersections(m).intersects) << "a sharp but open dihedral";
  m.add_triangle(1, 0, 4);
  const auto r = self_intersections(m);
  ASSERT_EQ(r.pairs, 1u) << "folded onto each other";
  EXPECT_EQ(r.sample[0], std::make_pair(Index{0}, Index{3}));
}

TEST(SelfIntersections, SharedVertexCountsOnlyBeyondIt) {
  // Two tetrahedra sharing one vertex slot, apart otherwise (a non-manifold vertex): the
  // second is moved so that its B lands on the first's D = (0, 1, 0); the first lies in
  // y <= 1 and the second in y >= 1, touching at D only.
  IndexedMesh two =
      test::disjoint_union(test::tetrahedron_fig_2_13(), test::translated(test::tetrahedron_fig_2_13(), V3(0, 1, 1)));
  const Index D = 3, B2 = 4 + 1;
  for (auto& t : two.F)
    for (auto& v : t)
      if (v == B2) v = D;
  EXPECT_FALSE(self_intersections(TriMesh<double>::from_indexed(two)).intersects);
  // The same contact through two different slots at the same position is a touch, and
  // touching counts.
  const IndexedMesh touching =
      test::disjoint_union(test::tetrahedron_fig_2_13(), test::translated(test::tetrahedron_fig_2_13(), V3(0, 1, 1)));
  EXPECT_TRUE(self_intersections(TriMesh<double>::from_indexed(touching)).intersects);
}

TEST(SelfIntersections, BrokenTopologyIsDiagnosedNotRefused) {
  // A fin: a third triangle on an edge of a tetrahedron (non-manifold edge), pointing out.
  IndexedMesh fin = test::tetrahedron_fig_2_13();
  fin.V.push_back(V3(0, -2, 3));
  fin.F.push_back({1, 0, 4});  // on edge (A, B), away from the solid
  EXPECT_FALSE(self_intersections(TriMesh<double>::from_indexed(fin)).intersects);
  // One face flipped (inconsistent orientation): orientation does not matter here.
  IndexedMesh flipped = test::cube12();
  std::swap(flipped.F[3][1], flipped.F[3][2]);
  EXPECT_FALSE(self_intersections(TriMesh<double>::from_indexed(flipped)).intersects);
  // A duplicated face overlaps its twin.
  IndexedMesh doubled = test::cube12();
  doubled.F.push_back(doubled.F[5]);
  const auto r = self_intersections(TriMesh<double>::from_indexed(doubled));
  ASSERT_EQ(r.pairs, 1u);
  EXPECT_EQ(r.sample[0], std::make_pair(Index{5}, Index{12}));
}

TEST(SelfIntersections, DegenerateTriangleIsReportedWithItself) {
  IndexedMesh m = test::cube12();
  m.V.push_back(V3(3, 3, 3));
  m.V.push_back(V3(4, 4, 4));
  m.V.push_back(V3(5, 5, 5));
  m.F.push_back({8, 9, 10});  // collinear corners
  const auto r = self_intersections(TriMesh<double>::from_indexed(m));
  ASSERT_EQ(r.pairs, 1u);
  EXPECT_EQ(r.sample[0], std::make_pair(Index{12}, Index{12}));
}

TEST(SelfIntersections, CorruptLiveTriangleThrowsInvariantError) {
  TriMesh<double> bad_index = TriMesh<double>::from_indexed(test::cube12());
  bad_index.triangle[4][2] = 99;
  EXPECT_THROW(self_intersections(bad_index), InvariantError);
  TriMesh<double> nan_corner = TriMesh<double>::from_indexed(test::cube12());
  nan_corner.position.x()[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(self_intersections(nan_corner), InvariantError);
}

TEST(SelfIntersections, StressSizedSphereIsClean) {
  IndexedMesh sphere = test::icosphere(kStressSphereLevel);
  // Deterministic radial ripple so the mesh is not perfectly regular.
  for (std::size_t k = 0; k < sphere.V.size(); ++k)
    sphere.V[k] *= 1.0 + kStressNoise * std::sin(12.9898 * static_cast<double>(k));
  const TriMesh<double> md = TriMesh<double>::from_indexed(sphere);
  const TriMesh<float> mf = md.cast<float>();
  ASSERT_EQ(md.live_triangle_count(), 81920u);
  const auto t0 = std::chrono::steady_clock::now();
  const auto rd = self_intersections(md);
  const auto t1 = std::chrono::steady_clock::now();
  const auto rf = self_intersections(mf);
  const auto t2 = std::chrono::steady_clock::now();
  EXPECT_FALSE(rd.intersects);
  EXPECT_FALSE(rf.intersects);
  const double ms_double = std::chrono::duration<double, std::milli>(t1 - t0).count();
  const double ms_float = std::chrono::duration<double, std::milli>(t2 - t1).count();
  std::cout << "[ timing   ] self_intersections on " << md.live_triangle_count() << " triangles: double " << ms_double
            << " ms, float " << ms_float << " ms\n";
  RecordProperty("ms_double", std::to_string(ms_double));
  RecordProperty("ms_float", std::to_string(ms_float));
}

}  // namespace
}  // namespace meltlab::sim
