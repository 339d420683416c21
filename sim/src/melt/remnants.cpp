// Removal of inverted parts (harness safety net, see MeltParams::remnant_check_every).
// Connected parts come from a union-find over the live triangles; each part's signed
// volume is the divergence-theorem sum of its triangles, accumulated in double. A closed
// part with correct (outward) orientation has positive volume; <= 0 means it is inside out
// or flat, i.e. it has melted through itself.

#include "../mesh/union_find.h"
#include "workspace.h"

namespace meltlab::sim {

template <class Real>
std::int64_t remove_inverted_parts_pass(TriMesh<Real>& m, MeltWorkspace& ws) {
  const std::size_t nv = m.vertex_slots(), nt = m.triangle_slots();
  UnionFind& parts = ws.remnant_parts;
  parts.reset(nv);
  for (std::size_t t = 0; t < nt; ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    parts.unite(tri[0], tri[1]);
    parts.unite(tri[0], tri[2]);
  }
  parts.flatten();
  const std::vector<Index>& parent = parts.parent;  // each slot's root
  // Corners from the packed copy of the positions when it is current (the same numbers; one
  // cache line per corner instead of three).
  const std::vector<Real>& packed = ws.packed_positions<Real>();
  const bool use_packed = ws.packed_valid && packed.size() == 3 * nv + 1;
  auto corner = [&](Index v) {
    const auto vs = static_cast<std::size_t>(v);
    if (use_packed) return Vec3<double>(packed[3 * vs], packed[3 * vs + 1], packed[3 * vs + 2]);
    return Vec3<double>(m.position[vs].template cast<double>());
  };
  std::vector<double>& six_volume = ws.part_six_volume;
  six_volume.assign(nv, 0.0);
  for (std::size_t t = 0; t < nt; ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    const Vec3<double> a = corner(tri[0]), b = corner(tri[1]), c = corner(tri[2]);
    six_volume[static_cast<std::size_t>(parent[static_cast<std::size_t>(tri[0])])] += a.dot(b.cross(c));
  }
  std::int64_t removed = 0;
  std::vector<std::uint8_t>& doomed = ws.part_doomed;
  doomed.assign(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    if (!m.vertex_alive[v] || parent[v] != static_cast<Index>(v)) continue;
    if (ws.adj.built() && ws.adj.of(static_cast<Index>(v)).empty()) continue;
    if (six_volume[v] <= 0.0) {
      doomed[v] = 1;
      ++removed;
    }
  }
  if (removed == 0) return 0;
  ws.schedule.invalidate();
  for (std::size_t t = 0; t < nt; ++t)
    if (m.triangle_alive[t] && doomed[static_cast<std::size_t>(parent[static_cast<std::size_t>(m.triangle[t][0])])])
      m.triangle_alive[t] = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!m.vertex_alive[v] || !doomed[static_cast<std::size_t>(parent[v])]) continue;
    m.vertex_alive[v] = 0;
    m.triangle_count[v] = 0;
    if (ws.adj.built()) ws.adj.assign(static_cast<Index>(v), {});
  }
  return removed;
}

template <class Real>
std::int64_t remove_inverted_parts(TriMesh<Real>& m) {
  MeltWorkspace ws;
  return remove_inverted_parts_pass(m, ws);
}

template std::int64_t remove_inverted_parts_pass(TriMesh<float>&, MeltWorkspace&);
template std::int64_t remove_inverted_parts_pass(TriMesh<double>&, MeltWorkspace&);
template std::int64_t remove_inverted_parts(TriMesh<float>&);
template std::int64_t remove_inverted_parts(TriMesh<double>&);

}  // namespace meltlab::sim
