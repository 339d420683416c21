// Compaction of a melting mesh (sim/src/melt/compact.cpp), white box: the arrays compacted in
// place, side by side on threads, equal the live elements of the mesh before, in order, serially
// and in parallel alike, and the workspace's triangle lists are those of the compacted mesh.

#include "workspace.h"

#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/melt.h>

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace meltlab::sim {
namespace {

// The passes of MeltSimulator::step() without its compaction, `cycles` times, serially.
template <class Real>
void melt_without_compaction(TriMesh<Real>& m, MeltWorkspace& ws, const MeltParams& p, int cycles) {
  const auto kl = make_constant_kl(1.0);
  prepare_workspace(ws, m);
  for (int c = 1; c <= cycles; ++c) {
    deform_pass(m, p, *kl, Execution::kSerial, ws);
    CycleReport r;
    collapse_pass(m, p.kr, p.merge, Execution::kSerial, ws, r);
    if (r.merged_vertices > 0) {
      glued_pass(m, ws, r);
      repair_pass(m, ws, r, Execution::kSerial);
    }
    ws.schedule.touch(ws.dirty_list);
    ws.clear_dirty();
  }
}

template <class Real>
void expect_lists_as_built(const VertexTriangles& adj, const TriMesh<Real>& m, const std::string& what) {
  VertexTriangles fresh;
  fresh.build(m);
  ASSERT_TRUE(adj.built()) << what;
  ASSERT_EQ(adj.vertex_count(), fresh.vertex_count()) << what;
  for (std::size_t v = 0; v < m.vertex_slots(); ++v) {
    const auto a = adj.of(static_cast<Index>(v)), b = fresh.of(static_cast<Index>(v));
    ASSERT_EQ(std::vector<Index>(a.begin(), a.end()), std::vector<Index>(b.begin(), b.end()))
        << what << ", vertex " << v;
  }
}

template <class Real>
void check_compaction(const IndexedMesh& mesh, double kr_rel, int cycles, const std::string& name) {
  const MeltParams p = relative_melt_params(mesh, 0.05, kr_rel);
  TriMesh<Real> ms = TriMesh<Real>::from_indexed(mesh), mp = ms;
  MeltWorkspace ws_s, ws_p;
  melt_without_compaction(ms, ws_s, p, cycles);
  melt_without_compaction(mp, ws_p, p, cycles);
  ASSERT_LT(ms.live_triangle_count(), ms.triangle_slots()) << name << ": the melt must leave dead slots";
  ASSERT_GE(ms.triangle_slots(), std::size_t{1} << 14) << name << ": large enough for the parallel path";
  // What compaction must give: the live elements in order, corners renumbered.
  std::vector<Index> new_vertex(ms.vertex_slots(), -1);
  Index nv = 0;
  for (std::size_t v = 0; v < ms.vertex_slots(); ++v)
    if (ms.vertex_alive[v]) new_vertex[v] = nv++;
  const std::size_t nt = ms.live_triangle_count();
  std::vector<Real> px, fnz;
  std::vector<Index> count;
  std::vector<Triangle> tri;
  for (std::size_t v = 0; v < ms.vertex_slots(); ++v)
    if (ms.vertex_alive[v]) px.push_back(ms.position.x()[v]), count.push_back(ms.triangle_count[v]);
  for (std::size_t t = 0; t < ms.triangle_slots(); ++t)
    if (ms.triangle_alive[t]) {
      Triangle k = ms.triangle[t];
      for (Index& v : k) v = new_vertex[static_cast<std::size_t>(v)];
      tri.push_back(k), fnz.push_back(ms.face_normal.z()[t]);
    }
  TriMesh<Real> plain = ms;  // compact_mesh alone returns the new vertex indices
  EXPECT_EQ(compact_mesh(plain, Execution::kSerial), new_vertex) << name;
  compact_workspace(ms, ws_s, Execution::kSerial);
  compact_workspace(mp, ws_p, Execution::kParallel);
  expect_lists_as_built(ws_s.adj, ms, name + ", serial compaction");
  expect_lists_as_built(ws_p.adj, mp, name + ", parallel compaction");
  EXPECT_EQ(ms.vertex_slots(), static_cast<std::size_t>(nv)) << name;
  EXPECT_EQ(ms.triangle_slots(), nt) << name;
  EXPECT_EQ(ms.position.x(), px) << name;
  EXPECT_EQ(ms.triangle_count, count) << name;
  EXPECT_EQ(ms.triangle, tri) << name;
  EXPECT_EQ(ms.face_normal.z(), fnz) << name;
  // Serial and parallel: the same bytes in every array.
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(ms.position.column(a), mp.position.column(a)) << name;
    EXPECT_EQ(ms.normal.column(a), mp.normal.column(a)) << name;
    EXPECT_EQ(ms.displacement.column(a), mp.displacement.column(a)) << name;
    EXPECT_EQ(ms.face_normal.column(a), mp.face_normal.column(a)) << name;
  }
  EXPECT_EQ(ms.triangle, mp.triangle) << name;
  EXPECT_EQ(ms.triangle_count, mp.triangle_count) << name;
  EXPECT_EQ(ms.reindex, mp.reindex) << name;
  EXPECT_EQ(ms.vertex_alive, std::vector<std::uint8_t>(ms.vertex_slots(), 1)) << name;
  EXPECT_EQ(ms.triangle_alive, mp.triangle_alive) << name;
  // The melt goes on the same from both.
  melt_without_compaction(ms, ws_s, p, 5);
  melt_without_compaction(mp, ws_p, p, 5);
  EXPECT_EQ(ms.position.x(), mp.position.x()) << name << ", 5 cycles later";
  EXPECT_EQ(ms.triangle, mp.triangle) << name << ", 5 cycles later";
}

TEST(Compaction, InPlaceAndSideBySideGiveTheLiveElementsInOrder) {
  const IndexedMesh c = datasets::benchmark_object('C');  // the poles collapse first: dead slots
  check_compaction<float>(c, 0.5, 30, "object C float");
  check_compaction<double>(c, 0.5, 30, "object C double");
  check_compaction<double>(datasets::geodesic_sphere(40, 0.05), 0.98, 6, "geodesic 32k, many merges");
}

}  // namespace
}  // namespace meltlab::sim
