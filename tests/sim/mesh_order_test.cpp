// Renumbering for locality (mesh_order.h): Morton and breadth-first orders are permutations
// that keep every position and every triangle's orientation; the breadth-first order is one
// (a breadth-first search of the output visits its vertices as 0, 1, 2, ...), so an edge's two
// ends lie in the same or in adjacent levels.

#include <meltlab/datasets/molds.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/mesh_order.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

namespace meltlab::sim {
namespace {

// The output is the input renumbered: the maps are permutations, the positions move with their
// vertices, each output triangle is its input triangle's corners renumbered and rotated (the
// same cyclic order, so the same orientation), and the triangles are sorted.
void expect_renumbering(const IndexedMesh& in, const Reordered& r, const std::string& what) {
  ASSERT_EQ(r.mesh.V.size(), in.V.size()) << what;
  ASSERT_EQ(r.mesh.F.size(), in.F.size()) << what;
  std::vector<Index> seen(in.V.size(), 0);
  for (std::size_t v = 0; v < in.V.size(); ++v) {
    const auto n = static_cast<std::size_t>(r.new_from_old_vertex[v]);
    ASSERT_LT(n, in.V.size()) << what;
    ++seen[n];
    EXPECT_EQ(r.mesh.V[n], in.V[v]) << what;
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](Index c) { return c == 1; })) << what << ": not a permutation";
  std::vector<Index> used(in.F.size(), 0);
  for (std::size_t t = 0; t < in.F.size(); ++t) {
    const auto old = static_cast<std::size_t>(r.old_from_new_triangle[t]);
    ASSERT_LT(old, in.F.size()) << what;
    ++used[old];
    Triangle mapped;
    for (std::size_t k = 0; k < 3; ++k) mapped[k] = r.new_from_old_vertex[static_cast<std::size_t>(in.F[old][k])];
    EXPECT_EQ(r.mesh.F[t], rotate_min_first(mapped)) << what << ": triangle " << t;
  }
  EXPECT_TRUE(std::all_of(used.begin(), used.end(), [](Index c) { return c == 1; })) << what;
  EXPECT_TRUE(std::is_sorted(r.mesh.F.begin(), r.mesh.F.end())) << what;
}

// A breadth-first search of `m` (each component from its lowest unvisited index, neighbours in
// ascending index); returns the order of the visits.
std::vector<Index> breadth_first_visits(const IndexedMesh& m) {
  std::vector<std::vector<Index>> nb(m.V.size());
  for (const Triangle& f : m.F)
    for (std::size_t k = 0; k < 3; ++k) {
      nb[static_cast<std::size_t>(f[k])].push_back(f[(k + 1) % 3]);
      nb[static_cast<std::size_t>(f[(k + 1) % 3])].push_back(f[k]);
    }
  for (auto& l : nb) std::sort(l.begin(), l.end());
  std::vector<Index> order;
  std::vector<bool> queued(m.V.size(), false);
  for (std::size_t s = 0; s < m.V.size(); ++s) {
    if (queued[s]) continue;
    queued[s] = true;
    order.push_back(static_cast<Index>(s));
    for (std::size_t head = order.size() - 1; head < order.size(); ++head)
      for (Index w : nb[static_cast<std::size_t>(order[head])])
        if (!queued[static_cast<std::size_t>(w)]) {
          queued[static_cast<std::size_t>(w)] = true;
          order.push_back(w);
        }
  }
  return order;
}

std::vector<std::pair<std::string, IndexedMesh>> shapes() {
  IndexedMesh two = datasets::icosphere(3);
  const IndexedMesh torus = datasets::torus(3.0, 0.5, 40, 16);
  const auto base = static_cast<Index>(two.V.size());
  for (const auto& v : torus.V) two.V.push_back(v);
  for (const auto& f : torus.F) two.F.push_back({f[0] + base, f[1] + base, f[2] + base});
  return {{"object C", datasets::benchmark_object('C')},
          {"giraffe", datasets::mold_mesh(datasets::Mold::kGiraffe)},
          {"sphere inside a torus (two components)", two},
          {"empty", IndexedMesh{}}};
}

TEST(MeshOrder, MortonAndBreadthFirstAreRenumberings) {
  for (const auto& [name, m] : shapes()) {
    expect_renumbering(m, reorder_for_locality(m), name + " morton");
    expect_renumbering(m, reorder_breadth_first(m), name + " breadth-first");
  }
}

TEST(MeshOrder, BreadthFirstOrderIsABreadthFirstSearchOfItsOutput) {
  for (const auto& [name, m] : shapes()) {
    const IndexedMesh out = reorder_breadth_first(m).mesh;
    const std::vector<Index> visits = breadth_first_visits(out);
    std::size_t out_of_order = 0;
    for (std::size_t k = 0; k < visits.size(); ++k) out_of_order += visits[k] != static_cast<Index>(k) ? 1 : 0;
    EXPECT_EQ(out_of_order, 0u) << name;
    // The Morton order is not one (else this test could not tell them apart).
    if (!m.F.empty()) {
      const std::vector<Index> morton_visits = breadth_first_visits(reorder_for_locality(m).mesh);
      std::size_t moved = 0;
      for (std::size_t k = 0; k < morton_visits.size(); ++k) moved += morton_visits[k] != static_cast<Index>(k) ? 1 : 0;
      EXPECT_GT(moved, 0u) << name;
    }
  }
}

}  // namespace
}  // namespace meltlab::sim
