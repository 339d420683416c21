// Alg. 3: glued-triangle removal and index re-sorting (monograph §3.2, Fig. 3.7).
// A vertex of a valid closed mesh is on at least three triangles, so a vertex on exactly
// two marks a glued pair: both triangles and the vertex are deleted. The counts are taken
// before any deletion (as in the monograph); a pair that this single test misses is left to
// the repair pass. Surviving triangles are rotated min-index first, which Alg. 2 needs.

#include "workspace.h"

namespace meltlab::sim {

template <class Real>
void glued_pass(TriMesh<Real>& m, Execution exec, MeltWorkspace& ws, CycleReport& report) {
  resize_vertex_scratch(ws, m);
  const std::size_t nv = m.vertex_slots();
  const std::size_t nt = m.triangle_slots();
  std::vector<Index>& count = m.triangle_count;

  // ---- t: live triangles per vertex ----
  for_range(exec, nv, [&](std::size_t b, std::size_t e) {
    for (std::size_t v = b; v < e; ++v) count[v] = 0;
  });
  if (exec == Execution::kSerial) {
    for (std::size_t t = 0; t < nt; ++t)
      if (m.triangle_alive[t])
        for (Index v : m.triangle[t]) ++count[static_cast<std::size_t>(v)];
  } else {
    for_range(exec, nt, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t)
        if (m.triangle_alive[t])
          for (Index v : m.triangle[t]) atomic_increment(count[static_cast<std::size_t>(v)]);
    });
  }

  // ---- delete triangles on a count-2 vertex; rotate the others min-index first ----
  std::atomic<std::int64_t> glued{0};
  for_range(exec, nt, [&](std::size_t b, std::size_t e) {
    std::int64_t local = 0;
    for (std::size_t t = b; t < e; ++t) {
      if (!m.triangle_alive[t]) continue;
      Triangle& tri = m.triangle[t];
      if (count[static_cast<std::size_t>(tri[0])] == 2 || count[static_cast<std::size_t>(tri[1])] == 2 ||
          count[static_cast<std::size_t>(tri[2])] == 2) {
        m.triangle_alive[t] = 0;
        ++local;
        for (Index v : tri) atomic_flag_set(ws.dirty[static_cast<std::size_t>(v)]);
        continue;
      }
      tri = rotate_min_first(tri);
    }
    glued.fetch_add(local, std::memory_order_relaxed);
  });
  report.glued_triangles += glued.load();

  // ---- delete count-2 vertices (glued) and count-0 vertices (orphans) ----
  std::int64_t glued_v = 0, orphans = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!m.vertex_alive[v]) continue;
    if (count[v] == 2) {
      m.vertex_alive[v] = 0;
      ++glued_v;
    } else if (count[v] == 0) {
      m.vertex_alive[v] = 0;
      ++orphans;
    }
  }
  report.glued_vertices += glued_v;
  report.orphan_vertices += orphans;
}

template <class Real>
CycleReport remove_glued_and_sort(TriMesh<Real>& m, Execution exec) {
  MeltWorkspace ws;
  CycleReport report;
  glued_pass(m, exec, ws, report);
  return report;
}

template <class Real>
void sort_triangle_indices(TriMesh<Real>& m) {
  for (std::size_t t = 0; t < m.triangle_slots(); ++t)
    if (m.triangle_alive[t]) m.triangle[t] = rotate_min_first(m.triangle[t]);
}

template void glued_pass(TriMesh<float>&, Execution, MeltWorkspace&, CycleReport&);
template void glued_pass(TriMesh<double>&, Execution, MeltWorkspace&, CycleReport&);
template CycleReport remove_glued_and_sort(TriMesh<float>&, Execution);
template CycleReport remove_glued_and_sort(TriMesh<double>&, Execution);
template void sort_triangle_indices(TriMesh<float>&);
template void sort_triangle_indices(TriMesh<double>&);

}  // namespace meltlab::sim
