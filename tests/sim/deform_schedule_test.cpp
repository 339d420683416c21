// The deformation sweep's schedule (sim/src/melt/deform_schedule.h), white box: a block it
// lets add without testing owners (block_mixed false) must hold no live triangle with a corner
// owned by another part, and in a mixed block every such triangle must be flagged (foreign(): only
// flagged triangles test their owners), after every update across collapses, repairs and remnant
// checks. The bitwise partition tests (simulator_test.cpp) cannot be relied on to see a block wrongly
// called unmixed or a triangle left unflagged: a part then adds into a record it does not own, which
// in a serial sweep is the same addition in the same order, and on threads a race that seldom shows
// on a small mesh (a broken flag update that cleared every changed flag did fail them too).

#include "deform_schedule.h"
#include "workspace.h"

#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/melt.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace meltlab::sim {
namespace {

// Whether live triangle t has a corner s gives another part than t's.
template <class Real>
bool triangle_has_foreign_corner(const DeformSchedule& s, const TriMesh<Real>& m, std::size_t t) {
  if (!m.triangle_alive[t]) return false;
  bool foreign = false;
  for (Index v : m.triangle[t]) foreign = foreign || s.owner(v) != s.part_of_triangle(t);
  return foreign;
}

// Whether block b of schedule s holds a live triangle with a corner s gives another part.
template <class Real>
bool has_foreign_corner(const DeformSchedule& s, const TriMesh<Real>& m, std::size_t b) {
  bool foreign = false;
  for (std::size_t t = b * kTriangleBlock; t < std::min(m.triangle_slots(), (b + 1) * kTriangleBlock); ++t)
    foreign = foreign || triangle_has_foreign_corner(s, m, t);
  return foreign;
}

// Whether group g has no live vertex with triangles (it may be called interior to any part).
template <class Real>
bool free_group(const TriMesh<Real>& m, const VertexTriangles& adj, std::int32_t g) {
  bool free = true;
  for (std::size_t v = static_cast<std::size_t>(g) * kGroup;
       v < std::min(m.vertex_slots(), (static_cast<std::size_t>(g) + 1) * kGroup); ++v)
    free = free && (!m.vertex_alive[v] || adj.of(static_cast<Index>(v)).empty());
  return free;
}

// Blocks the schedule calls unmixed although a live triangle in them has a foreign corner, live
// triangles with a foreign corner that it does not flag (foreign(), which in a mixed block decides
// which triangles test their owners), and owners or interior groups that would change the order of
// a vertex's additions (below), for `m` as it is: all must be 0 (a block called
// mixed that no longer is, or a dead slot still flagged, is allowed); a schedule built afresh must
// be exact in both.
template <class Real>
std::size_t check_blocks(const DeformSchedule& s, const TriMesh<Real>& m, const VertexTriangles& adj,
                         std::size_t parts) {
  std::size_t wrong = 0;
  for (std::size_t b = 0; b < s.blocks(); ++b) wrong += !s.block_mixed(b) && has_foreign_corner(s, m, b);
  for (std::size_t t = 0; t < m.triangle_slots(); ++t)
    wrong += s.foreign()[t] == 0 && triangle_has_foreign_corner(s, m, t);
  DeformSchedule fresh;
  fresh.update(m, adj, parts);
  // Owners and the groups' classes after an update must keep the sums' order: a live vertex's owner
  // is no later than the part of its first triangle (its owner part adds its triangles of that part
  // first, the halo phase the others' in ascending order), and a group is interior to part p only if
  // every live vertex in it has all its triangles in p and is owned by p; any other group is a halo
  // group (an update may leave a group halo, or a dead vertex's owner, that a rebuild would not:
  // that costs time, not bits). Every group is classified once.
  std::vector<std::int32_t> may_be(s.groups(), 0);  // the part a group may be interior to, or kHalo
  for (std::size_t g = 0; g < s.groups(); ++g) {
    std::int64_t part = -1;
    bool halo = false;
    for (std::size_t v = g * kGroup; v < std::min(m.vertex_slots(), (g + 1) * kGroup); ++v) {
      const auto list = adj.of(static_cast<Index>(v));
      if (!m.vertex_alive[v] || list.empty()) continue;
      const std::size_t own = s.owner(static_cast<Index>(v));
      const std::size_t first = s.part_of_triangle(static_cast<std::size_t>(list.front()));
      const std::size_t last = s.part_of_triangle(static_cast<std::size_t>(list.back()));
      wrong += own > first;
      halo = halo || own != first || last != first || (part >= 0 && static_cast<std::size_t>(part) != first);
      part = static_cast<std::int64_t>(first);
    }
    may_be[g] = halo ? DeformSchedule::kHalo : static_cast<std::int32_t>(std::max<std::int64_t>(part, 0));
  }
  std::size_t classified = s.halo_groups().size();
  for (std::size_t p = 0; p < parts; ++p) {
    classified += s.interior_groups(p).size();
    for (std::int32_t g : s.interior_groups(p)) {
      const std::int32_t allowed = may_be[static_cast<std::size_t>(g)];
      wrong += allowed == DeformSchedule::kHalo || (allowed != static_cast<std::int32_t>(p) && !free_group(m, adj, g));
    }
  }
  wrong += classified != s.groups();
  for (std::size_t b = 0; b < fresh.blocks(); ++b)
    EXPECT_EQ(fresh.block_mixed(b), has_foreign_corner(fresh, m, b)) << "a fresh schedule is exact, block " << b;
  for (std::size_t t = 0; t < m.triangle_slots(); ++t)
    EXPECT_EQ(fresh.foreign()[t] != 0, triangle_has_foreign_corner(fresh, m, t))
        << "a fresh schedule flags exactly, triangle " << t;
  return wrong;
}

// A mesh melting on the passes of MeltSimulator::step(), serially, in its own workspace with the
// sweep in `parts` parts.
template <class Real>
struct PassMelt {
  TriMesh<Real> m;
  MeltParams p;
  KlFieldPtr kl = make_constant_kl(1.0);
  MeltWorkspace ws;
  PassMelt(const IndexedMesh& mesh, double kr_rel, std::size_t parts)
      : m(TriMesh<Real>::from_indexed(mesh)), p(relative_melt_params(mesh, 0.05, kr_rel)) {
    prepare_workspace(ws, m);
    ws.deform_parts = parts;
  }
  void deform() { deform_pass(m, p, *kl, Execution::kSerial, ws); }
  // The passes after the deformation, with the schedule told whose triangle lists changed: the
  // vertices merged, and whether any list changed.
  std::pair<std::int64_t, bool> after_deform() {
    CycleReport r;
    collapse_pass(m, p.kr, p.merge, Execution::kSerial, ws, r);
    if (r.merged_vertices > 0) {
      glued_pass(m, ws, r);
      repair_pass(m, ws, r, Execution::kSerial);
    }
    const bool touched = !ws.dirty_list.empty();
    ws.schedule.touch(ws.dirty_list);
    ws.clear_dirty();
    return {r.merged_vertices, touched};
  }
};

// The cycle of MeltSimulator::step() on the passes, checking the schedule after each deformation.
template <class Real>
void check_cycles(const IndexedMesh& mesh, double kr_rel, std::size_t parts, int cycles, const std::string& name) {
  PassMelt<Real> melt(mesh, kr_rel, parts);
  TriMesh<Real>& m = melt.m;
  MeltWorkspace& ws = melt.ws;
  std::int64_t merged = 0, updates_after_merges = 0, mixed_blocks = 0;
  bool touched = false;  // the last cycle changed triangle lists: this update is incremental
  for (int c = 1; c <= cycles; ++c) {
    melt.deform();
    ASSERT_EQ(check_blocks(ws.schedule, m, ws.adj, parts), 0u)
        << name << ", cycle " << c << ": blocks called unmixed or triangles unflagged with a foreign corner";
    updates_after_merges += touched;
    for (std::size_t b = 0; b < ws.schedule.blocks(); ++b) mixed_blocks += ws.schedule.block_mixed(b);
    const auto [merges, lists_changed] = melt.after_deform();
    merged += merges;
    touched = lists_changed;
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

// Two schedules give the same sweep: the same parts, interior and halo groups, owners and mixed
// blocks.
void expect_same_schedule(const DeformSchedule& a, const DeformSchedule& b, std::size_t vertices,
                          const std::string& what) {
  ASSERT_EQ(a.parts(), b.parts()) << what;
  ASSERT_EQ(a.blocks(), b.blocks()) << what;
  ASSERT_EQ(a.groups(), b.groups()) << what;
  for (std::size_t p = 0; p < a.parts(); ++p) {
    const auto x = a.interior_groups(p), y = b.interior_groups(p);
    EXPECT_TRUE(std::equal(x.begin(), x.end(), y.begin(), y.end())) << what << ": interior groups of part " << p;
  }
  const auto hx = a.halo_groups(), hy = b.halo_groups();
  EXPECT_TRUE(std::equal(hx.begin(), hx.end(), hy.begin(), hy.end())) << what << ": halo groups";
  std::size_t owners_differ = 0, mixed_differ = 0;
  for (std::size_t v = 0; v < vertices; ++v)
    owners_differ += a.owner(static_cast<Index>(v)) != b.owner(static_cast<Index>(v));
  for (std::size_t k = 0; k < a.blocks(); ++k) mixed_differ += a.block_mixed(k) != b.block_mixed(k);
  EXPECT_EQ(owners_differ, 0u) << what;
  EXPECT_EQ(mixed_differ, 0u) << what;
}

// An update on the threads (groups classified and triangles flagged side by side, the blocks'
// counts changed atomically) gives the serial update's schedule, and a rebuild on the threads the
// serial rebuild's, through a melt with merges.
// Every live vertex is touched on top of the cycle's own, so that the update splits into tasks
// (from 512 touched vertices, and from 512 touched groups on); the real merges change owners and
// flags. Returns the blocks whose mixed flag the updates changed.
std::size_t check_update_on_threads(const IndexedMesh& mesh, double kr_rel, std::size_t parts, int cycles,
                                    const std::string& name) {
  PassMelt<double> melt(mesh, kr_rel, parts);
  const TriMesh<double>& m = melt.m;
  MeltWorkspace& ws = melt.ws;
  std::int64_t merged = 0;
  std::size_t flags_changed = 0;
  for (int c = 1; c <= cycles; ++c) {
    melt.deform();
    merged += melt.after_deform().first;
    std::vector<Index> live;
    for (std::size_t v = 0; v < m.vertex_slots(); ++v)
      if (m.vertex_alive[v]) live.push_back(static_cast<Index>(v));
    if (live.size() < 512) break;  // no split into tasks any more
    DeformSchedule serial = ws.schedule, threads = ws.schedule;
    serial.touch(live), threads.touch(live);
    serial.update(m, ws.adj, parts, Execution::kSerial);
    threads.update(m, ws.adj, parts, Execution::kParallel);
    expect_same_schedule(serial, threads, m.vertex_slots(), name + ", cycle " + std::to_string(c));
    DeformSchedule built_serially, built_on_threads;  // rebuilt from scratch
    built_serially.update(m, ws.adj, parts, Execution::kSerial);
    built_on_threads.update(m, ws.adj, parts, Execution::kParallel);
    expect_same_schedule(built_serially, built_on_threads, m.vertex_slots(),
                         name + ", cycle " + std::to_string(c) + ", rebuilt");
    for (std::size_t k = 0; k < serial.blocks(); ++k)
      flags_changed += serial.block_mixed(k) != ws.schedule.block_mixed(k);
    if (::testing::Test::HasFailure()) break;
  }
  EXPECT_GT(merged, 0) << name << ": the melt must merge";
  return flags_changed;
}

TEST(DeformSchedule, UpdateOnThreadsGivesTheSerialSchedule) {
  // Object C: ~12 000 vertices, so the groups too are classified in tasks.
  check_update_on_threads(datasets::benchmark_object('C'), 0.5, 3, 40, "object C, 3 parts");
  // Many merges (2 200 vertices left after the first cycles): blocks' flags change on the threads.
  EXPECT_GT(check_update_on_threads(datasets::geodesic_sphere(20, 0.05), 0.98, 7, 20, "geodesic, 7 parts"), 0u)
      << "the updates must change some blocks' flags";
}

// The parts share the work, not just the blocks: a part sweeps the live triangles of its blocks
// and moves the vertices it owns (a move weighs half a triangle). On object C after 20 cycles
// (the cycle benchmark's state: merges and a compaction), equal numbers of blocks gave the first
// part 63 % of the vertices (1249 against 730 interior groups).
TEST(DeformSchedule, PartsShareTheSweepAndTheMoves) {
  const IndexedMesh c = datasets::benchmark_object('C');
  MeltSimulator<double> sim(TriMesh<double>::from_indexed(c), relative_melt_params(c), make_constant_kl(1.0));
  for (int cycle = 0; cycle < 20; ++cycle) sim.step();
  const TriMesh<double>& m = sim.mesh();
  VertexTriangles adj;
  adj.build(m);
  for (std::size_t parts : {2, 3, 7}) {
    DeformSchedule s;
    s.update(m, adj, parts);
    ASSERT_EQ(s.parts(), parts);
    std::vector<double> work(parts, 0.0);
    double block_max = 0;
    for (std::size_t b = 0; b < s.blocks(); ++b) {
      double w = 0;
      for (std::size_t t = b * kTriangleBlock; t < std::min(m.triangle_slots(), (b + 1) * kTriangleBlock); ++t)
        w += m.triangle_alive[t] ? 1.0 : 0.0;
      block_max = std::max(block_max, w);
      work[s.part_of_triangle(b * kTriangleBlock)] += w;
    }
    std::vector<std::size_t> owned(parts, 0);
    for (std::size_t v = 0; v < m.vertex_slots(); ++v)
      if (m.vertex_alive[v] && !adj.of(static_cast<Index>(v)).empty()) {
        work[s.owner(static_cast<Index>(v))] += 0.5;
        ++owned[s.owner(static_cast<Index>(v))];
      }
    double total = 0;
    for (double w : work) total += w;
    // A boundary falls on a block: each part is within one block's work (its triangles and the
    // vertices it owns, at most 3 per triangle) of an equal share.
    for (std::size_t p = 0; p < parts; ++p)
      EXPECT_NEAR(work[p], total / static_cast<double>(parts), 2.5 * block_max)
          << parts << " parts, part " << p << " owns " << owned[p] << " vertices";
  }
}

}  // namespace
}  // namespace meltlab::sim
