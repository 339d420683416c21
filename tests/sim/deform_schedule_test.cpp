// The deformation sweep's schedule (sim/src/melt/deform_schedule.h), white box: a block it
// lets add without testing owners (block_mixed false) must hold no live triangle with a corner
// owned by another part, after every update across collapses, repairs and remnant checks. The
// bitwise partition tests (simulator_test.cpp) cannot see a block wrongly called unmixed: a part
// then adds into a record it does not own, which in a serial sweep is the same addition in the
// same order, and on threads a race that seldom shows on a small mesh.

#include "deform_schedule.h"
#include "workspace.h"

#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/melt.h>

#include <gtest/gtest.h>

#include <string>

namespace meltlab::sim {
namespace {

// Blocks the schedule calls unmixed although a live triangle in them has a foreign corner
// (must be 0), and blocks it calls mixed that a fresh schedule of the same partition does not
// (allowed: a triangle that died keeps its flag until the next rebuild), for `m` as it is.
template <class Real>
std::pair<std::size_t, std::size_t> check_blocks(const DeformSchedule& s, const TriMesh<Real>& m,
                                                 const VertexTriangles& adj, std::size_t parts) {
  DeformSchedule fresh;
  fresh.update(m, adj, parts);
  std::size_t wrong = 0, stale = 0;
  for (std::size_t b = 0; b < s.blocks(); ++b) {
    bool foreign = false;
    for (std::size_t t = b * kTriangleBlock; t < std::min(m.triangle_slots(), (b + 1) * kTriangleBlock); ++t) {
      if (!m.triangle_alive[t]) continue;
      for (Index v : m.triangle[t]) foreign = foreign || s.owner(v) != s.part_of_triangle(t);
    }
    if (foreign && !s.block_mixed(b)) ++wrong;
    if (s.block_mixed(b) && !fresh.block_mixed(b)) ++stale;
    EXPECT_EQ(fresh.block_mixed(b), foreign) << "a fresh schedule is exact, block " << b;
  }
  return {wrong, stale};
}

// The cycle of MeltSimulator::step() on the passes, checking the schedule after each deformation.
template <class Real>
void check_cycles(const IndexedMesh& mesh, double kr_rel, std::size_t parts, int cycles, const std::string& name) {
  TriMesh<Real> m = TriMesh<Real>::from_indexed(mesh);
  const MeltParams p = relative_melt_params(mesh, 0.05, kr_rel);
  const auto kl = make_constant_kl(1.0);
  MeltWorkspace ws;
  prepare_workspace(ws, m);
  ws.deform_parts = parts;
  std::int64_t merged = 0, updates_after_merges = 0, mixed_blocks = 0;
  bool touched = false;  // the last cycle changed triangle lists: this update is incremental
  for (int c = 1; c <= cycles; ++c) {
    deform_pass(m, p, *kl, Execution::kSerial, ws);
    const auto [wrong, stale] = check_blocks(ws.schedule, m, ws.adj, parts);
    ASSERT_EQ(wrong, 0u) << name << ", cycle " << c << ": blocks called unmixed with a foreign corner";
    updates_after_merges += touched;
    for (std::size_t b = 0; b < ws.schedule.blocks(); ++b) mixed_blocks += ws.schedule.block_mixed(b);
    CycleReport r;
    collapse_pass(m, p.kr, p.merge, Execution::kSerial, ws, r);
    merged += r.merged_vertices;
    if (r.merged_vertices > 0) {
      glued_pass(m, ws, r);
      repair_pass(m, ws, r, Execution::kSerial);
    }
    touched = !ws.dirty_list.empty();
    ws.schedule.touch(ws.dirty_list);
    ws.clear_dirty();
    if (c % 16 == 0) remove_inverted_parts_pass(m, ws, Execution::kSerial);
  }
  EXPECT_GT(merged, 0) << name << ": the check must cover collapses";
  EXPECT_GT(updates_after_merges, 0) << name << ": and updates of the schedule after them";
  EXPECT_GT(mixed_blocks, 0) << name << ": and blocks that must test the owners";
}

TEST(DeformSchedule, BlocksWithoutTestsHoldNoForeignCornerAcrossCycles) {
  const IndexedMesh c = datasets::benchmark_object('C');
  check_cycles<float>(c, 0.5, 2, 60, "object C float, 2 parts");
  check_cycles<double>(c, 0.5, 3, 60, "object C double, 3 parts");
  const IndexedMesh geodesic = datasets::geodesic_sphere(20, 0.05);
  check_cycles<double>(geodesic, 0.98, 7, 20, "geodesic (many merges), 7 parts");
  check_cycles<double>(datasets::dumbbell(), 0.5, 2, 300, "dumbbell (repairs), 2 parts");
}

}  // namespace
}  // namespace meltlab::sim
