// Alg. 2: short-edge collapse (monograph §3.2, Eq. 3.7, Fig. 3.6, Fig. 3.11).
//
// Mark: each live triangle (a, b, c), a the smallest index, tests its edges in the order
// ab, bc, ca and marks at most one (if/else-if, as in the monograph). The higher index of a
// short edge is to be merged into the lower one. Several triangles may mark the same
// vertex with different targets (the monograph's `reindex_conflict_policy`): the smallest
// target wins, which is independent of the order the triangles are visited in, so serial
// and parallel runs mark identically.
// Chains: targets are always smaller indices, so every chain ends at a root and an
// ascending sweep resolves it in O(n) (root[k] = root[target[k]], target[k] < k).
// Merge (`merge_position_mode`): cluster mean (GPU §5.4, default) or the CPU's sequential
// pairwise mean; both sum a cluster's members in ascending index order.
// Re-point + delete degenerate triangles; the triangle counts for Alg. 3 are taken in the
// same sweep. Vertices around every re-pointed triangle are marked dirty for the repair.

#include "workspace.h"

#include <meltlab/sim/error.h>

#include <fmt/format.h>

namespace meltlab::sim {

namespace {
// Chains strictly decrease (target[k] < k), so an ascending sweep finds every root in O(n):
// root[target[k]] is final by the time k is reached. Returns the number of merged vertices.
std::int64_t flatten_chains(const Index* target, Index* root, std::size_t n) {
  std::int64_t merged = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const Index t = target[v];
    root[v] = t == static_cast<Index>(v) ? t : root[static_cast<std::size_t>(t)];
    merged += root[v] != static_cast<Index>(v) ? 1 : 0;
  }
  return merged;
}
}  // namespace

std::vector<Index> flatten_merge_targets(const std::vector<Index>& target) {
  for (std::size_t v = 0; v < target.size(); ++v)
    if (target[v] < 0 || target[v] > static_cast<Index>(v))
      throw InvariantError(fmt::format("merge target of v{} is v{}; targets must not exceed the index", v, target[v]));
  std::vector<Index> root(target.size());
  flatten_chains(target.data(), root.data(), target.size());
  return root;
}

template <class Real>
void collapse_pass(TriMesh<Real>& m, double kr, MergeMode merge, Execution exec, MeltWorkspace& ws,
                   CycleReport& report) {
  resize_vertex_scratch(ws, m);
  const std::size_t nv = m.vertex_slots();
  const std::size_t nt = m.triangle_slots();
  const auto kr2 = static_cast<Real>(kr * kr);
  std::vector<Index>& target = m.reindex;

  for_range(exec, nv, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) target[v] = static_cast<Index>(v);
  });

  // ---- mark ----
  const bool parallel = exec == Execution::kParallel;
  for_range(exec, nt, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      if (!m.triangle_alive[t]) continue;
      const Triangle& tri = m.triangle[t];
      const Vec3<Real>& pa = m.position[static_cast<std::size_t>(tri[0])];
      const Vec3<Real>& pb = m.position[static_cast<std::size_t>(tri[1])];
      const Vec3<Real>& pc = m.position[static_cast<std::size_t>(tri[2])];
      Index from = -1, to = -1;
      if ((pb - pa).squaredNorm() < kr2) {
        from = tri[1], to = tri[0];
      } else if ((pc - pb).squaredNorm() < kr2) {
        from = std::max(tri[1], tri[2]), to = std::min(tri[1], tri[2]);
      } else if ((pa - pc).squaredNorm() < kr2) {
        from = tri[2], to = tri[0];
      }
      if (from < 0) continue;
      Index& slot = target[static_cast<std::size_t>(from)];
      if (parallel)
        atomic_min(slot, to);
      else if (to < slot)
        slot = to;
    }
  });

  // ---- flatten chains (ascending: target[k] < k is already resolved) ----
  std::vector<Index>& root = ws.root;
  const std::int64_t merged = flatten_chains(target.data(), root.data(), nv);
  report.merged_vertices += merged;
  if (merged == 0) return;

  // ---- merge positions, in ascending member order (identical for both executions) ----
  ws.touched_roots.clear();
  for (std::size_t v = 0; v < nv; ++v) {
    const auto r = static_cast<std::size_t>(root[v]);
    target[v] = root[v];  // the monograph's i after flattening
    if (r == v) continue;
    if (merge == MergeMode::kSequentialPairwise) {
      m.position[r] = (m.position[v] + m.position[r]) / Real(2);
    } else {
      if (ws.cluster_size[r] == 0) {
        ws.touched_roots.push_back(static_cast<Index>(r));
        ws.cluster_size[r] = 1;
      }
      m.position[r] += m.position[v];
      ++ws.cluster_size[r];
    }
    m.vertex_alive[v] = 0;
    ws.dirty[r] = 1;
  }
  for (Index r : ws.touched_roots) {
    auto& size = ws.cluster_size[static_cast<std::size_t>(r)];
    m.position[static_cast<std::size_t>(r)] /= static_cast<Real>(size);
    size = 0;
  }

  // ---- re-point corners, delete degenerate triangles ----
  std::int64_t degenerate = 0;
  if (exec == Execution::kSerial) {
    for (std::size_t t = 0; t < nt; ++t) {
      if (!m.triangle_alive[t]) continue;
      Triangle& tri = m.triangle[t];
      const Triangle old = tri;
      for (Index& v : tri) v = root[static_cast<std::size_t>(v)];
      if (tri == old) continue;
      for (Index v : tri) ws.dirty[static_cast<std::size_t>(v)] = 1;
      if (is_degenerate(tri)) {
        m.triangle_alive[t] = 0;
        ++degenerate;
      }
    }
  } else {
    std::atomic<std::int64_t> deg{0};
    for_range(exec, nt, [&](std::size_t b, std::size_t e) {
      std::int64_t local = 0;
      for (std::size_t t = b; t < e; ++t) {
        if (!m.triangle_alive[t]) continue;
        Triangle& tri = m.triangle[t];
        const Triangle old = tri;
        for (Index& v : tri) v = root[static_cast<std::size_t>(v)];
        if (tri == old) continue;
        for (Index v : tri) atomic_flag_set(ws.dirty[static_cast<std::size_t>(v)]);
        if (is_degenerate(tri)) {
          m.triangle_alive[t] = 0;
          ++local;
        }
      }
      deg.fetch_add(local, std::memory_order_relaxed);
    });
    degenerate = deg.load();
  }
  report.degenerate_triangles += degenerate;
}

template <class Real>
CycleReport collapse_short_edges(TriMesh<Real>& m, double kr, MergeMode merge, Execution exec) {
  if (!(kr >= 0.0) || !std::isfinite(kr)) throw InputError("kr: must be a finite number >= 0");
  MeltWorkspace ws;
  CycleReport report;
  collapse_pass(m, kr, merge, exec, ws, report);
  return report;
}

template void collapse_pass(TriMesh<float>&, double, MergeMode, Execution, MeltWorkspace&, CycleReport&);
template void collapse_pass(TriMesh<double>&, double, MergeMode, Execution, MeltWorkspace&, CycleReport&);
template CycleReport collapse_short_edges(TriMesh<float>&, double, MergeMode, Execution);
template CycleReport collapse_short_edges(TriMesh<double>&, double, MergeMode, Execution);

}  // namespace meltlab::sim
