// Alg. 3: glued-triangle removal and index re-sorting (monograph §3.2, Fig. 3.7).
// A vertex of a valid closed mesh is on at least three triangles, so a vertex on exactly
// two marks a glued pair: both triangles and the vertex are deleted; a vertex left on none
// is deleted too. The counts are taken before any deletion, as in the monograph; a pair
// this single test misses is left to the repair pass.
// Only vertices whose triangles changed this cycle (the dirty set) can have a count below
// three, so only they are examined; only re-pointed triangles can be out of order, and the
// collapse already rotated them, so the sort step has nothing left to do here.

#include "workspace.h"

#include <algorithm>

namespace meltlab::sim {

template <class Real>
void glued_pass(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report) {
  prepare_workspace(ws, m);
  std::vector<Index> glued_vertices, orphans;
  for (Index v : ws.dirty_list) {
    const auto vs = static_cast<std::size_t>(v);
    if (!m.vertex_alive[vs]) continue;
    const auto count = static_cast<Index>(ws.adj.of(v).size());
    m.triangle_count[vs] = count;
    if (count == 2)
      glued_vertices.push_back(v);
    else if (count == 0)
      orphans.push_back(v);
  }
  std::vector<Index> killed;
  for (Index v : glued_vertices)
    for (Index t : ws.adj.of(v))
      if (m.triangle_alive[static_cast<std::size_t>(t)]) {
        m.triangle_alive[static_cast<std::size_t>(t)] = 0;
        killed.push_back(t);
      }
  for (Index v : glued_vertices) {
    m.vertex_alive[static_cast<std::size_t>(v)] = 0;
    ws.adj.assign(v, {});
  }
  for (Index v : orphans) m.vertex_alive[static_cast<std::size_t>(v)] = 0;
  for (Index t : killed)
    for (Index v : m.triangle[static_cast<std::size_t>(t)]) {
      if (!m.vertex_alive[static_cast<std::size_t>(v)]) continue;
      ws.adj.erase(v, t);
      ws.mark_dirty(v);
    }
  report.glued_triangles += static_cast<std::int64_t>(killed.size());
  report.glued_vertices += static_cast<std::int64_t>(glued_vertices.size());
  report.orphan_vertices += static_cast<std::int64_t>(orphans.size());
}

template <class Real>
CycleReport remove_glued_and_sort(TriMesh<Real>& m, Execution) {
  MeltWorkspace ws;
  prepare_workspace(ws, m);
  sort_triangle_indices(m);
  for (std::size_t v = 0; v < m.vertex_slots(); ++v)
    if (m.vertex_alive[v]) ws.mark_dirty(static_cast<Index>(v));
  CycleReport report;
  glued_pass(m, ws, report);
  return report;
}

template <class Real>
void sort_triangle_indices(TriMesh<Real>& m) {
  for (std::size_t t = 0; t < m.triangle_slots(); ++t)
    if (m.triangle_alive[t]) m.triangle[t] = rotate_min_first(m.triangle[t]);
}

template void glued_pass(TriMesh<float>&, MeltWorkspace&, CycleReport&);
template void glued_pass(TriMesh<double>&, MeltWorkspace&, CycleReport&);
template CycleReport remove_glued_and_sort(TriMesh<float>&, Execution);
template CycleReport remove_glued_and_sort(TriMesh<double>&, Execution);
template void sort_triangle_indices(TriMesh<float>&);
template void sort_triangle_indices(TriMesh<double>&);

}  // namespace meltlab::sim
