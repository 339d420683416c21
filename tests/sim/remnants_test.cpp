// The remnant check (sim/src/melt/remnants.cpp) in a workspace that lives across checks, white box:
// it reuses the connected parts while the triangles and their alive flags are unchanged, and finds
// them afresh when either changes, so every check removes exactly what a check in a fresh
// workspace removes.

#include "workspace.h"

#include "hand_meshes.h"

#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/melt.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <string>
#include <utility>
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

// The smallest vertex of each vertex's connected part (over the live triangles; a vertex in none is
// its own), by repeated relaxation along the triangles' edges until nothing changes: a reference
// that shares no code with the union-find.
std::vector<Index> smallest_of_part(const TriMesh<double>& m) {
  std::vector<Index> low(m.vertex_slots());
  std::iota(low.begin(), low.end(), 0);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
      if (!m.triangle_alive[t]) continue;
      Index lo = low[static_cast<std::size_t>(m.triangle[t][0])];
      for (Index v : m.triangle[t]) lo = std::min(lo, low[static_cast<std::size_t>(v)]);
      for (Index v : m.triangle[t]) {
        Index& l = low[static_cast<std::size_t>(v)];
        if (l != lo) l = lo, changed = true;
      }
    }
  }
  return low;
}

// Rem's unions with splicing (the check's) against finds with path halving and a link of the larger
// root under the smaller: the same parents after flatten() (each slot's smallest part member), for
// random pairs in random orders, few enough to leave many parts; and before flatten() no slot's
// parent is larger than the slot (what makes one ascending pass of flatten() enough).
TEST(Remnants, SplicedUnionsGiveTheParentsOfLinkedFinds) {
  std::mt19937 rng(17);
  for (int round = 0; round < 20; ++round) {
    const std::size_t n = 500 + rng() % 3000;
    std::vector<std::pair<Index, Index>> pairs(n * (round % 4 + 1) / 4);
    std::uniform_int_distribution<Index> any(0, static_cast<Index>(n) - 1);
    for (auto& [a, b] : pairs) a = any(rng), b = any(rng);
    UnionFind linked(n), spliced(n);
    for (const auto& [a, b] : pairs) {  // both roots found, the larger hung under the smaller
      const Index ra = linked.find(a), rb = linked.find(b);
      linked.parent[static_cast<std::size_t>(std::max(ra, rb))] = std::min(ra, rb);
    }
    std::shuffle(pairs.begin(), pairs.end(), rng);
    for (const auto& [a, b] : pairs) spliced.unite(a, b);
    for (std::size_t v = 0; v < n; ++v) ASSERT_LE(spliced.parent[v], static_cast<Index>(v)) << "round " << round;
    linked.flatten(), spliced.flatten();
    EXPECT_EQ(spliced.parent, linked.parent) << "round " << round << ", " << pairs.size() << " pairs on " << n;
  }
}

// The parts the check finds (each slot's root after flatten: the smallest index of its part) against
// the reference, serial and on the threads (more than 2 x 2048 triangles: the volumes are summed in chunks), on
// twelve spheres and forty strips with their vertices renumbered at random, in their generated
// triangle order (consecutive unions share corners: short spliced walks) and shuffled (long ones),
// with every fifth triangle dead (a sphere may fall apart into pieces, a strip does).
TEST(Remnants, PartsAreTheSmallestVertexOfEachComponent) {
  IndexedMesh all;
  for (int p = 0; p < 12; ++p)
    all = test::disjoint_union(std::move(all), test::translated(datasets::icosphere(3, 1.0), {3.0 * p, 0, 0}));
  // And 40 strips of 100 triangles (i, i + 1, i + 2): each edge in at most two triangles, so a wrong
  // link is seldom mended by a later union as it is on a sphere.
  for (int p = 0; p < 40; ++p) {
    IndexedMesh strip;
    for (int i = 0; i < 102; ++i) strip.V.emplace_back(0.1 * i, 5.0 + p, double(i % 2));
    for (Index i = 0; i < 100; ++i) strip.F.push_back({i, i + 1, i + 2});
    all = test::disjoint_union(std::move(all), strip);
  }
  ASSERT_GT(all.F.size(), 2u * 2048u);
  std::vector<Index> new_index(all.V.size());
  std::iota(new_index.begin(), new_index.end(), 0);
  std::mt19937 rng(5);
  std::shuffle(new_index.begin(), new_index.end(), rng);
  const IndexedMesh renumbered = test::renumbered(all, new_index);
  for (int order = 0; order < 2; ++order)
    for (bool holes : {false, true}) {
      IndexedMesh mesh = renumbered;
      if (order == 1) std::shuffle(mesh.F.begin(), mesh.F.end(), rng);
      TriMesh<double> base = TriMesh<double>::from_indexed(mesh);
      if (holes)
        for (std::size_t t = 0; t < base.triangle_slots(); t += 5) base.triangle_alive[t] = 0;
      const std::vector<Index> expected = smallest_of_part(base);
      for (Execution exec : {Execution::kSerial, Execution::kParallel}) {
        TriMesh<double> m = base;
        MeltWorkspace ws;
        remove_inverted_parts_pass(m, ws, exec);
        const std::string what = std::string(order == 0 ? "generated order" : "shuffled order") +
                                 (holes ? ", holes" : "") + (exec == Execution::kSerial ? ", serial" : ", threads");
        ASSERT_EQ(ws.remnant_parts.parent.size(), expected.size()) << what;
        std::size_t wrong = 0;
        for (std::size_t v = 0; v < expected.size(); ++v) wrong += ws.remnant_parts.parent[v] != expected[v];
        EXPECT_EQ(wrong, 0u) << what;
      }
    }
}

// On the threads the parts' volumes are summed in chunks, in another order than the serial check's
// ordered sums; only a sign the chunked sum certifies (further from zero than the two orders' error
// bound) is taken from it, otherwise the ordered sum decides. Flat closed parts (a geodesic sphere
// squashed onto a plane off the origin: volume zero, terms that are not) have sums that are rounding
// noise of either sign: the decisions on threads must be the serial ones in every case, beside a
// correct sphere and an inverted one, whose signs the chunked sums certify. More than 2 x 2048
// triangles, so that the chunks run on the threads.
TEST(Remnants, ChunkedVolumesOnTheThreadsDecideAsTheOrderedSums) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 4);
  const IndexedMesh sphere = datasets::geodesic_sphere(12, 1.0);  // 2 880 triangles
  IndexedMesh inverted = test::translated(sphere, {3, 0, 0});
  for (auto& t : inverted.F) std::swap(t[1], t[2]);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> offset(-50.0, 50.0), slope(-0.3, 0.3);
  int flat_removed = 0, flat_kept = 0;
  for (int trial = 0; trial < 40; ++trial) {
    // A plane z = c + a x + b y, far from the origin, holding a squashed sphere.
    IndexedMesh flat = sphere;
    const double c = offset(rng), a = slope(rng), b = slope(rng);
    for (auto& v : flat.V) v = {v.x() + 6.0, v.y(), c + a * (v.x() + 6.0) + b * v.y()};
    const IndexedMesh mesh = test::disjoint_union(test::disjoint_union(sphere, inverted), flat);
    ASSERT_GT(mesh.F.size(), 2u * 2048u);
    TriMesh<double> serial = TriMesh<double>::from_indexed(mesh), on_threads = serial;
    MeltWorkspace serial_ws, threads_ws;
    const std::int64_t removed = remove_inverted_parts_pass(serial, serial_ws, Execution::kSerial);
    EXPECT_EQ(remove_inverted_parts_pass(on_threads, threads_ws, Execution::kParallel), removed) << "trial " << trial;
    EXPECT_EQ(on_threads.triangle_alive, serial.triangle_alive) << "trial " << trial;
    EXPECT_EQ(on_threads.vertex_alive, serial.vertex_alive) << "trial " << trial;
    EXPECT_TRUE(serial.vertex_alive[0]) << "the sphere stays";
    EXPECT_FALSE(serial.vertex_alive[sphere.V.size()]) << "the inverted sphere goes";
    (serial.vertex_alive[2 * sphere.V.size()] ? flat_kept : flat_removed) += 1;
  }
  // The flat parts' ordered sums fell on both sides of zero: the decisions above depended on rounding.
  EXPECT_GT(flat_removed, 0);
  EXPECT_GT(flat_kept, 0);
}

}  // namespace
}  // namespace meltlab::sim
