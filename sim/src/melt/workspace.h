#pragma once
// Private to the melt cycle: scratch arrays kept across cycles and small helpers shared by
// the passes. Not installed.

#include <meltlab/sim/melt.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

namespace meltlab::sim {

/// Grain of the TBB loops: large enough that task overhead stays below ~1% of a pass.
inline constexpr std::size_t kParallelGrain = 2048;

struct MeltWorkspace {
  // Parallel deform: vertex -> incident (triangle, corner) lists in ascending triangle
  // order (CSR), and per-triangle unit edge vectors computed before the gather.
  std::vector<std::int32_t> adj_offset;  // size V + 1
  std::vector<std::int32_t> adj_cursor;  // size V
  std::vector<std::int32_t> adj_entry;   // 3T entries: triangle * 3 + corner
  std::vector<float> unit_edges_f;       // 9 per triangle (float meshes)
  std::vector<double> unit_edges_d;      // 9 per triangle (double meshes)

  // Collapse: flattened merge target of every vertex, and merge accumulators.
  std::vector<Index> root;
  std::vector<std::int32_t> cluster_size;
  std::vector<Index> touched_roots;

  // Topology repair: vertices whose neighbourhood changed this cycle.
  std::vector<std::uint8_t> dirty;
  std::vector<Index> dirty_list;

  template <class Real>
  std::vector<Real>& unit_edges() {
    if constexpr (std::is_same_v<Real, float>) return unit_edges_f;
    else return unit_edges_d;
  }
};

/// v / |v|, or the zero vector if |v|² is zero (open choice `zero_guard`: a degenerate
/// triangle or a vanished edge contributes nothing instead of NaN).
template <class Real>
inline Vec3<Real> normalized_or_zero(const Vec3<Real>& v) {
  const Real n2 = v.squaredNorm();
  if (!(n2 > Real(0))) return Vec3<Real>::Zero();
  return v / std::sqrt(n2);
}

/// Runs body(begin, end) over [0, n) serially or as TBB tasks.
template <class Body>
inline void for_range(Execution exec, std::size_t n, const Body& body) {
  if (exec == Execution::kSerial || n < 2 * kParallelGrain) {
    body(std::size_t{0}, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kParallelGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
}

/// x = min(x, value), atomically (the order of concurrent calls cannot change the result).
inline void atomic_min(Index& x, Index value) {
  std::atomic_ref<Index> ref(x);
  Index cur = ref.load(std::memory_order_relaxed);
  while (value < cur && !ref.compare_exchange_weak(cur, value, std::memory_order_relaxed)) {
  }
}

inline void atomic_increment(std::int32_t& x) {
  std::atomic_ref<std::int32_t>(x).fetch_add(1, std::memory_order_relaxed);
}

inline void atomic_flag_set(std::uint8_t& x) { std::atomic_ref<std::uint8_t>(x).store(1, std::memory_order_relaxed); }

inline bool is_degenerate(const Triangle& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

/// Grows the per-vertex workspace arrays to the mesh's slot count (splits add slots).
template <class Real>
void resize_vertex_scratch(MeltWorkspace& ws, const TriMesh<Real>& m) {
  const std::size_t n = m.vertex_slots();
  if (ws.dirty.size() < n) ws.dirty.resize(n, 0);
  if (ws.root.size() < n) ws.root.resize(n);
  if (ws.cluster_size.size() < n) ws.cluster_size.resize(n, 0);
}

// Pass implementations shared by the free functions and MeltSimulator.
template <class Real>
void deform_pass(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec, MeltWorkspace& ws);
template <class Real>
void collapse_pass(TriMesh<Real>& m, double kr, MergeMode merge, Execution exec, MeltWorkspace& ws,
                   CycleReport& report);
template <class Real>
void glued_pass(TriMesh<Real>& m, Execution exec, MeltWorkspace& ws, CycleReport& report);
template <class Real>
void repair_pass(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report);

}  // namespace meltlab::sim
