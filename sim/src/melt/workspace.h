#pragma once
// Private to the melt cycle: the state kept across cycles (vertex -> triangle lists,
// per-triangle unit edges) and helpers shared by the passes. Not installed.

#include "adjacency.h"
#include "deform_schedule.h"
#include "lanes.h"
#include "triangle_kernels.h"
#include "../mesh/union_find.h"

#include <meltlab/sim/melt.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <iterator>
#include <cmath>
#include <cstdint>
#include <memory>
#include <limits>
#include <type_traits>
#include <vector>

namespace meltlab::sim {

/// Grain of the TBB loops: large enough that task overhead stays below ~1% of a pass.
inline constexpr std::size_t kParallelGrain = 2048;

/// What a triangle contributes to its corners in Alg. 1: the unit face normal and, per
/// corner, the unit edge vector to the next corner.
template <class Real>
struct TriangleTerms {
  Vec3<Real> normal;
  Vec3<Real> edge[3];
};

/// Terms of the triangles of a parallel sweep that have a corner owned by an earlier part,
/// indexed by triangle slot. Only those slots are written (and read), so the array is
/// allocated without initialisation: the pages nobody writes are never touched (the 871k
/// dragon's 68 MB in double, of which the part boundary uses a few pages; zeroing them all
/// cost ~30 ms whenever a simulator started).
template <class Real>
struct StoredTerms {
  std::unique_ptr<TriangleTerms<Real>[]> slot;
  std::size_t size = 0;
  void ensure(std::size_t n) {
    if (size >= n) return;
    slot = std::make_unique_for_overwrite<TriangleTerms<Real>[]>(n);
    size = n;
  }
};

/// A vertex's sums in Alg. 1 as one record: the face normals (lanes 0-2) and the unit edges
/// from the vertex (lanes 3-5) of its triangles; lanes 6-7 stay 0. One record per vertex, so
/// the serial scatter adds a corner's terms with one SIMD addition (lane by lane: the same
/// additions in the same order as three-component sums; the compiler does not merge the
/// scalar read-modify-writes of a plain array into one), and the vertex moves read eight
/// records as one 8×8 block (transpose8).
template <class Real>
struct VertexSums {
  Lanes<Real> lane = {};
};
static_assert(sizeof(VertexSums<float>) == kLanes * sizeof(float));
static_assert(sizeof(VertexSums<double>) == kLanes * sizeof(double));

struct MeltWorkspace {
  VertexTriangles adj;      ///< triangles of every vertex, ascending; kept up to date by every pass
  DeformSchedule schedule;  ///< the order of the deformation sweep (deform_schedule.h)
  /// Parts of the deformation sweep: 0 = one per thread TBB may use (1 for a serial cycle or
  /// a small mesh); tests set it to exercise other partitions (any count gives the same mesh).
  std::size_t deform_parts = 0;
  /// Alg. 1 writes the mesh's N, M and Nf columns (vertex normals, moves, face normals). No
  /// pass of the cycle reads them (each computes what it needs), so MeltSimulator turns this
  /// off unless asked (set_record_vectors); `deform()` alone keeps it on.
  bool record_vectors = true;

  // Deform: terms (unit normal + 3 unit edges) of the triangles of a parallel sweep that have a
  // corner owned by an earlier part, indexed by triangle slot (only those slots are written).
  StoredTerms<float> terms_f;
  StoredTerms<double> terms_d;
  // Deform: per-vertex sums. The sweep relies on them being zero (`sums_zero`: its groups clear
  // their records when they move; false until the first sweep, which clears them all).
  std::vector<VertexSums<float>> sums_f;
  std::vector<VertexSums<double>> sums_d;
  bool sums_zero = false;
  // Deform and collapse: a copy of the positions as packed triples (pack_positions()), from
  // which the sweep gathers triangle corners and the short-edge test reads them (one load per
  // corner instead of three from the columns). The vertex moves read the old positions from
  // it and write the new ones to it and to the columns (a vertex moves after its last
  // triangle, so no gather needs the old value afterwards); the collapse pass writes the roots
  // it moves; any other change of positions (repair, compaction) clears `packed_valid`, and
  // the next pass that reads it copies all positions again.
  std::vector<float> packed_f;
  std::vector<double> packed_d;
  bool packed_valid = false;

  // Conservative skip of the short-edge test. This cycle's deformation sweep, which computes
  // every edge's squared length anyway, stores each triangle's shortest one (`min_edge2`, +inf
  // for a dead slot) from the positions before the moves; an edge shrinks in the moves by at
  // most twice the largest vertex move (plus rounding), so the short-edge test that follows
  // skips every triangle whose key is above (kr + 2 cycle_move_bound)² with a safety margin,
  // and tests the others exactly. `min_edge2_current` says the keys are this cycle's (a
  // short-edge test without a deformation before it tests every triangle).
  // The keys are floats in both precisions (rounded down), half the bytes for double meshes.
  std::vector<float> min_edge2;
  bool min_edge2_current = false;
  double cycle_move_bound = 0.0;  ///< this cycle's largest vertex move + rounding, mesh units

  /// Flattened merge target of every vertex: the identity between collapse passes (a pass
  /// sets the merged vertices' entries and puts them back), so a pass visits only those.
  std::vector<Index> root;
  /// The entries of m.reindex that may differ from their index (the last collapse's merged
  /// vertices, the repair's collapsed ones): the next short-edge test resets only these.
  /// `reindex_tracked` says the list is complete (else it resets every entry).
  std::vector<Index> reindex_changed;
  bool reindex_tracked = false;
  UnionFind remnant_parts;  ///< remnant check: the connected parts
  /// The triangles and alive flags remnant_parts was found from: the parts are a function of
  /// these and the vertex slot count alone, so the check reuses them while both are unchanged.
  std::vector<Triangle> remnant_triangles;
  std::vector<std::uint8_t> remnant_alive;
  std::vector<double> part_six_volume;  ///< remnant check: 6 x volume per part (at its root)
  /// Remnant check on the threads: a run of consecutive live triangles of one part in a chunk (the
  /// sum of their volume terms, of the terms' magnitudes, and their number), per chunk and then
  /// all of them ordered by part.
  struct VolumeRun {
    Index part;
    double sum, magnitude;
    std::int64_t terms;
  };
  std::vector<std::vector<VolumeRun>> volume_runs;
  std::vector<VolumeRun> volume_runs_sorted;
  std::vector<std::uint8_t> part_doomed;  ///< remnant check: the part is removed
  std::vector<Index> merged;              ///< vertices merged this cycle (ascending): those the short-edge test marked
  std::vector<std::int32_t> cluster_size;
  std::vector<Index> touched_roots;

  std::vector<std::uint8_t> dirty;  ///< vertex whose triangles changed this cycle
  std::vector<Index> dirty_list;    ///< the same vertices, in the order they were marked
  std::vector<Index> affected;      ///< triangles whose indices changed this cycle
  std::vector<Index> scratch;       ///< temporary list (merging sorted lists)

  template <class Real>
  StoredTerms<Real>& triangle_terms() {
    if constexpr (std::is_same_v<Real, float>)
      return terms_f;
    else
      return terms_d;
  }
  template <class Real>
  std::vector<Real>& packed_positions() {
    if constexpr (std::is_same_v<Real, float>)
      return packed_f;
    else
      return packed_d;
  }
  template <class Real>
  std::vector<VertexSums<Real>>& vertex_sums() {
    if constexpr (std::is_same_v<Real, float>)
      return sums_f;
    else
      return sums_d;
  }
  void mark_dirty(Index v) {
    auto& d = dirty[static_cast<std::size_t>(v)];
    if (!d) {
      d = 1;
      dirty_list.push_back(v);
    }
  }
  void clear_dirty() {
    for (Index v : dirty_list) dirty[static_cast<std::size_t>(v)] = 0;
    dirty_list.clear();
  }
};

/// Runs body(begin, end) over [0, n) serially or as TBB tasks of at least `grain` elements
/// (serially below two of them). The body must not depend on how the range is split (every
/// element's result is computed by the same code).
template <class Body>
inline void for_range(Execution exec, std::size_t n, const Body& body, std::size_t grain = kParallelGrain) {
  if (exec == Execution::kSerial || n < 2 * grain) {
    body(std::size_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

/// Runs body(item) for every item in order, having called stage1 on the item 2 kAhead ahead
/// and stage2 on the item kAhead ahead: stage1 prefetches what stage2 reads to prefetch what
/// the body reads (e.g. a vertex's list record, then its list). The passes after the
/// deformation visit a few scattered elements of a large mesh, mostly out of the cache; without
/// this, each element's misses were waited for one element at a time.
template <class Items, class Stage1, class Stage2, class Body>
inline void prefetched_for_each(const Items& items, const Stage1& stage1, const Stage2& stage2, const Body& body) {
  constexpr std::size_t kAhead = 8;
  const std::size_t n = std::size(items);
  for (std::size_t i = 0; i < std::min(n, 2 * kAhead); ++i) stage1(items[i]);
  for (std::size_t i = 0; i < std::min(n, kAhead); ++i) stage2(items[i]);
  for (std::size_t i = 0; i < n; ++i) {
    if (i + 2 * kAhead < n) stage1(items[i + 2 * kAhead]);
    if (i + kAhead < n) stage2(items[i + kAhead]);
    body(items[i]);
  }
}

inline bool is_degenerate(const Triangle& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

/// Position of v among the corners of t (v must be a corner).
inline int corner_of(const Triangle& t, Index v) { return t[0] == v ? 0 : (t[1] == v ? 1 : 2); }

/// Makes the workspace match the mesh: per-vertex arrays sized, adjacency built if needed.
template <class Real>
void prepare_workspace(MeltWorkspace& ws, const TriMesh<Real>& m) {
  const std::size_t n = m.vertex_slots();
  if (!ws.adj.built()) ws.adj.build(m);
  ws.adj.grow(n);
  if (ws.dirty.size() < n) ws.dirty.resize(n, 0);
  for (std::size_t v = ws.root.size(); v < n; ++v) ws.root.push_back(static_cast<Index>(v));
  if (ws.cluster_size.size() < n) ws.cluster_size.resize(n, 0);
}

// Pass implementations shared by the free functions and MeltSimulator.
template <class Real>
void deform_pass(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec, MeltWorkspace& ws);
template <class Real>
void collapse_pass(TriMesh<Real>& m, double kr, MergeMode merge, Execution exec, MeltWorkspace& ws,
                   CycleReport& report);
template <class Real>
void glued_pass(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report);
template <class Real>
void repair_pass(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report, Execution exec);
template <class Real>
std::int64_t remove_inverted_parts_pass(TriMesh<Real>& m, MeltWorkspace& ws, Execution exec);
/// Compacts the mesh (compact_mesh, arrays side by side in parallel) and brings the workspace
/// along: triangle lists rebuilt, the schedule and packed positions invalidated, per-vertex
/// scratch resized.
template <class Real>
void compact_workspace(TriMesh<Real>& m, MeltWorkspace& ws, Execution exec);

}  // namespace meltlab::sim
