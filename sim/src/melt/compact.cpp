// Order-preserving compaction of the mesh arrays (see MeltParams::compact_below).

#include "workspace.h"

namespace meltlab::sim {

namespace {
template <class T>
void keep(std::vector<T>& a, const std::vector<std::uint8_t>& alive) {
  std::size_t w = 0;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (alive[k]) a[w++] = a[k];
  a.resize(w);
  a.shrink_to_fit();
}
template <class Real>
void keep(Vec3Columns<Real>& a, const std::vector<std::uint8_t>& alive) {
  for (int axis = 0; axis < 3; ++axis) keep(a.column(axis), alive);
}
}  // namespace

template <class Real>
std::vector<Index> compact_mesh(TriMesh<Real>& m) {
  const std::size_t nv = m.vertex_slots();
  std::vector<Index> new_index(nv, -1);
  Index next = 0;
  for (std::size_t v = 0; v < nv; ++v)
    if (m.vertex_alive[v]) new_index[v] = next++;
  const std::vector<std::uint8_t> valive = m.vertex_alive;
  const std::vector<std::uint8_t> talive = m.triangle_alive;
  keep(m.position, valive);
  keep(m.normal, valive);
  keep(m.displacement, valive);
  keep(m.triangle_count, valive);
  keep(m.reindex, valive);
  keep(m.vertex_alive, valive);
  for (std::size_t v = 0; v < m.reindex.size(); ++v) m.reindex[v] = static_cast<Index>(v);
  keep(m.triangle, talive);
  keep(m.face_normal, talive);
  keep(m.triangle_alive, talive);
  // Increasing renumbering keeps every triangle's smallest index first.
  for (Triangle& t : m.triangle)
    for (Index& v : t) v = new_index[static_cast<std::size_t>(v)];
  return new_index;
}

template <class Real>
void compact_workspace(TriMesh<Real>& m, MeltWorkspace& ws) {
  compact_mesh(m);
  ws.clear_dirty();
  ws.adj.invalidate();
  ws.schedule.invalidate();
  ws.packed_valid = false;
  ws.dirty.assign(m.vertex_slots(), 0);
  ws.root.clear();             // identity again (prepare_workspace)
  ws.reindex_changed.clear();  // compact_mesh made m.reindex the identity
  ws.reindex_tracked = true;
  ws.cluster_size.assign(m.vertex_slots(), 0);
  prepare_workspace(ws, m);
}

template std::vector<Index> compact_mesh(TriMesh<float>&);
template std::vector<Index> compact_mesh(TriMesh<double>&);
template void compact_workspace(TriMesh<float>&, MeltWorkspace&);
template void compact_workspace(TriMesh<double>&, MeltWorkspace&);

}  // namespace meltlab::sim
