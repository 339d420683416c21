// Order-preserving compaction of the mesh arrays (see MeltParams::compact_below and
// compact_after).
//
// Every array is compacted in place and in order (live element k goes to the number of live
// elements before it), without a branch per element and without reallocating: the arrays keep
// their capacity, so a compaction neither frees nor faults in memory (it cannot grow the peak,
// which is the mesh before its first compaction). The arrays are independent, so in parallel
// they are compacted side by side, each by one task: the same bytes as serially. The triangle
// lists of the workspace are rebuilt (VertexTriangles::build: two streaming passes over the
// triangles; renumbering the old lists measured twice as slow on the 871k dragon, 13 against 6 ms,
// its reads of the triangles' new indices missing the caches).

#include "workspace.h"

#include <tbb/parallel_for.h>

#include <functional>
#include <numeric>

namespace meltlab::sim {

namespace {

// a[w] = a[k] for every k with alive[k], w counting them (w <= k: nothing is overwritten before
// it is read), storing every element and advancing w by the flag: no branch on the irregular
// flags of a melting mesh. n = a.size() = the number of flags.
template <class T>
void keep(std::vector<T>& a, const std::uint8_t* alive) {
  const std::size_t n = a.size();
  T* p = a.data();
  std::size_t w = 0;
  for (std::size_t k = 0; k < n; ++k) {
    p[w] = p[k];
    w += alive[k] != 0;
  }
  a.resize(w);
}

// The live vertices' new indices (-1 for dead slots) and their number.
std::vector<Index> new_indices(const std::vector<std::uint8_t>& alive, Index& live) {
  std::vector<Index> out(alive.size());
  Index next = 0;
  for (std::size_t k = 0; k < alive.size(); ++k) {
    out[k] = alive[k] ? next : -1;
    next += alive[k] != 0;
  }
  live = next;
  return out;
}

// Meshes below this many triangle slots are compacted on one thread (the tasks would cost more
// than they save).
constexpr std::size_t kParallelCompactSlots = 1u << 14;

}  // namespace

template <class Real>
std::vector<Index> compact_mesh(TriMesh<Real>& m, Execution exec) {
  Index live_vertices = 0;
  std::vector<Index> new_vertex = new_indices(m.vertex_alive, live_vertices);
  std::size_t live_triangles = 0;
  for (std::uint8_t a : m.triangle_alive) live_triangles += a != 0;
  const std::uint8_t* valive = m.vertex_alive.data();
  const std::uint8_t* talive = m.triangle_alive.data();
  // One job per array; the alive flags they read are compacted after all of them.
  std::vector<std::function<void()>> jobs;
  for (auto* columns : {&m.position, &m.normal, &m.displacement})
    for (int axis = 0; axis < 3; ++axis)
      jobs.push_back([columns, axis, valive] { keep(columns->column(axis), valive); });
  for (int axis = 0; axis < 3; ++axis) jobs.push_back([&m, axis, talive] { keep(m.face_normal.column(axis), talive); });
  jobs.push_back([&m, valive] { keep(m.triangle_count, valive); });
  // Increasing renumbering keeps every triangle's smallest index first.
  jobs.push_back([&m, &new_vertex, talive] {
    keep(m.triangle, talive);
    for (Triangle& t : m.triangle)
      for (Index& v : t) v = new_vertex[static_cast<std::size_t>(v)];
  });
  if (exec == Execution::kParallel && m.triangle_slots() >= kParallelCompactSlots)
    tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t j) { jobs[j](); });
  else
    for (const auto& job : jobs) job();
  m.reindex.resize(static_cast<std::size_t>(live_vertices));
  std::iota(m.reindex.begin(), m.reindex.end(), Index{0});
  m.vertex_alive.assign(static_cast<std::size_t>(live_vertices), 1);
  m.triangle_alive.assign(live_triangles, 1);
  return new_vertex;
}

template <class Real>
void compact_workspace(TriMesh<Real>& m, MeltWorkspace& ws, Execution exec) {
  compact_mesh(m, exec);
  ws.adj.invalidate();
  ws.clear_dirty();
  ws.schedule.invalidate();
  ws.packed_valid = false;
  ws.dirty.assign(m.vertex_slots(), 0);
  ws.root.clear();             // identity again (prepare_workspace)
  ws.reindex_changed.clear();  // compact_mesh made m.reindex the identity
  ws.reindex_tracked = true;
  ws.cluster_size.assign(m.vertex_slots(), 0);
  prepare_workspace(ws, m);
}

template std::vector<Index> compact_mesh(TriMesh<float>&, Execution);
template std::vector<Index> compact_mesh(TriMesh<double>&, Execution);
template void compact_workspace(TriMesh<float>&, MeltWorkspace&, Execution);
template void compact_workspace(TriMesh<double>&, MeltWorkspace&, Execution);

}  // namespace meltlab::sim
