#include <meltlab/sim/mesh_stats.h>
#include <meltlab/sim/topology.h>

#include "union_find.h"
#include "vertex_sort.h"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>

namespace meltlab::sim {

std::string TopologyProblem::describe() const {
  switch (kind) {
    case Kind::kBoundaryEdge:
      return fmt::format("open mesh: boundary edge (v{}, v{}) has only one face", a, b);
    case Kind::kNonManifoldEdge:
      return fmt::format("non-manifold edge (v{}, v{}) shared by {} faces", a, b, count);
    case Kind::kInconsistentOrientation:
      return fmt::format("inconsistent orientation: edge (v{}, v{}) used twice in the same direction", a, b);
    case Kind::kNonManifoldVertex:
      return fmt::format("non-manifold vertex v{}: its faces form {} separate fans", a, count);
    case Kind::kLowValence:
      return fmt::format("vertex v{} is on only {} face(s); a closed solid needs at least 3", a, count);
    case Kind::kDegenerateFace:
      return fmt::format("degenerate face {} repeats vertex v{}", b, a);
    case Kind::kOrphanVertex:
      return fmt::format("vertex v{} is live but no live face uses it", a);
    case Kind::kDeadVertexReference:
      return fmt::format("deleted vertex v{} is still used by a live face", a);
  }
  return "unknown topology problem";
}

namespace {

// Loops of a mesh given as flat arrays: loop k is verts[start[k] .. start[k+1]), and
// belongs to face face_of[k]. Vertex indices are slots in [0, n_slots).
struct Loops {
  std::size_t n_slots = 0;
  std::int64_t n_faces = 0;
  std::int64_t n_holes = 0;
  std::vector<Index> verts;
  std::vector<std::size_t> start{0};
  std::vector<Index> face_of;

  void add(const Index* v, std::size_t n, Index face) {
    verts.insert(verts.end(), v, v + n);
    start.push_back(verts.size());
    face_of.push_back(face);
  }
  std::size_t count() const { return face_of.size(); }
};

void add_problem(TopologyReport& r, std::size_t max_problems, TopologyProblem p) {
  if (r.problems.size() < max_problems) r.problems.push_back(p);
}

/// The vertices used by some loop, and the components (S) joined through loop edges.
struct Components {
  std::vector<std::uint8_t> used;
  UnionFind uf;
};

Components components_of(const Loops& L) {
  const std::size_t n = L.n_slots;
  std::vector<std::uint8_t> used(n, 0);
  UnionFind uf(n);
  for (std::size_t k = 0; k < L.count(); ++k) {
    const std::size_t s = L.start[k], e = L.start[k + 1];
    for (std::size_t j = s; j < e; ++j) {
      used[static_cast<std::size_t>(L.verts[j])] = 1;
      uf.unite(L.verts[j], L.verts[j + 1 < e ? j + 1 : s]);
    }
    // A hole loop belongs to the same shell as its face's outer loop (the face joins them).
    if (k > 0 && L.face_of[k] == L.face_of[k - 1]) uf.unite(L.verts[s], L.verts[L.start[k - 1]]);
  }

  return {std::move(used), std::move(uf)};
}

/// Every edge with the number of loops that use it in each direction: boundary, non-manifold
/// and misoriented edges into `r`; each edge counted once in its component's V - E + F - H.
/// Returns E.
std::int64_t check_edges(const Loops& L, UnionFind& uf, std::vector<std::int64_t>& comp_sum, TopologyReport& r,
                         std::size_t max_problems) {
  // Directed edges: key (lo, hi), forward = (from < to).
  struct DirEdge {
    std::uint64_t key;
    bool forward;
  };
  std::vector<DirEdge> edges;
  edges.reserve(L.verts.size());
  for (std::size_t k = 0; k < L.count(); ++k) {
    const std::size_t s = L.start[k], e = L.start[k + 1];
    for (std::size_t j = s; j < e; ++j) {
      const Index from = L.verts[j], to = L.verts[j + 1 < e ? j + 1 : s];
      const auto lo = static_cast<std::uint64_t>(std::min(from, to));
      const auto hi = static_cast<std::uint64_t>(std::max(from, to));
      edges.push_back({(lo << 32) | hi, from < to});
    }
  }
  sort_by_vertex_pair(edges, L.n_slots);  // equal keys adjacent; their order does not matter below

  std::int64_t E = 0;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    int fwd = 0, bwd = 0;
    while (j < edges.size() && edges[j].key == edges[i].key) {
      (edges[j].forward ? fwd : bwd) += 1;
      ++j;
    }
    const auto lo = static_cast<Index>(edges[i].key >> 32);
    const auto hi = static_cast<Index>(edges[i].key & 0xffffffffu);
    ++E;
    comp_sum[static_cast<std::size_t>(uf.find(lo))] -= 1;
    const int uses = fwd + bwd;
    if (uses == 1) {
      ++r.boundary_edges;
      add_problem(r, max_problems, {TopologyProblem::Kind::kBoundaryEdge, lo, hi, 1});
    } else if (uses > 2) {
      ++r.nonmanifold_edges;
      add_problem(r, max_problems, {TopologyProblem::Kind::kNonManifoldEdge, lo, hi, uses});
    } else if (fwd != 1 || bwd != 1) {
      ++r.misoriented_edges;
      add_problem(r, max_problems, {TopologyProblem::Kind::kInconsistentOrientation, lo, hi, uses});
    }
    i = j;
  }

  return E;
}

/// The corners around each vertex: low valence, and more than one fan (non-manifold vertex).
void check_vertex_fans(const Loops& L, TopologyReport& r, std::size_t max_problems) {
  struct Corner {
    Index v, prev, next;
  };
  std::vector<Corner> corners;
  corners.reserve(L.verts.size());
  for (std::size_t k = 0; k < L.count(); ++k) {
    const std::size_t s = L.start[k], e = L.start[k + 1];
    const std::size_t m = e - s;
    for (std::size_t j = 0; j < m; ++j)
      corners.push_back({L.verts[s + j], L.verts[s + (j + m - 1) % m], L.verts[s + (j + 1) % m]});
  }
  std::vector<Corner> scratch;
  counting_sort_by(corners, scratch, L.n_slots, [](const Corner& c) { return c.v; });
  std::vector<std::pair<Index, Index>> nb;  // (neighbour, corner) within one vertex
  for (std::size_t i = 0; i < corners.size();) {
    std::size_t j = i;
    while (j < corners.size() && corners[j].v == corners[i].v) ++j;
    const Index v = corners[i].v;
    const auto k = static_cast<Index>(j - i);
    if (k < 3) {
      ++r.low_valence_vertices;
      add_problem(r, max_problems, {TopologyProblem::Kind::kLowValence, v, -1, k});
    }
    nb.clear();
    for (std::size_t c = i; c < j; ++c) {
      nb.push_back({corners[c].prev, static_cast<Index>(c - i)});
      nb.push_back({corners[c].next, static_cast<Index>(c - i)});
    }
    std::sort(nb.begin(), nb.end());
    UnionFind fan(static_cast<std::size_t>(k));
    for (std::size_t a = 1; a < nb.size(); ++a)
      if (nb[a].first == nb[a - 1].first) fan.unite(nb[a].second, nb[a - 1].second);
    Index fans = 0;
    for (Index c = 0; c < k; ++c) fans += fan.find(c) == c ? 1 : 0;
    if (fans > 1) {
      ++r.nonmanifold_vertices;
      add_problem(r, max_problems, {TopologyProblem::Kind::kNonManifoldVertex, v, -1, fans});
    }
    i = j;
  }
}

/// The Euler counts (Eq. 2.3), the genus derived per component from its V - E + F - H.
void euler_counts(const Loops& L, std::int64_t E, Components& parts, std::vector<std::int64_t>& comp_sum,
                  EulerCounts& c) {
  const std::size_t n = L.n_slots;
  const std::vector<std::uint8_t>& used = parts.used;
  UnionFind& uf = parts.uf;
  c.E = E;
  c.F = L.n_faces;
  c.H = L.n_holes;
  for (std::size_t v = 0; v < n; ++v) {
    if (!used[v]) continue;
    ++c.V;
    comp_sum[static_cast<std::size_t>(uf.find(static_cast<Index>(v)))] += 1;
  }
  // Faces and holes: one per outer loop, holes counted negatively, at the loop's component.
  std::vector<std::uint8_t> is_outer(L.count(), 0);
  for (std::size_t k = 0; k < L.count(); ++k) is_outer[k] = (k == 0 || L.face_of[k] != L.face_of[k - 1]) ? 1 : 0;
  for (std::size_t k = 0; k < L.count(); ++k)
    comp_sum[static_cast<std::size_t>(uf.find(L.verts[L.start[k]]))] += is_outer[k] ? 1 : -1;
  finish_euler_counts(used, uf, comp_sum, c);
}

TopologyReport analyse(const Loops& L, std::size_t max_problems) {
  TopologyReport r;
  Components parts = components_of(L);
  std::vector<std::int64_t> comp_sum(L.n_slots, 0);  // V - E + F - H per component root
  const std::int64_t E = check_edges(L, parts.uf, comp_sum, r, max_problems);
  check_vertex_fans(L, r, max_problems);
  euler_counts(L, E, parts, comp_sum, r.counts);
  r.closed = r.boundary_edges == 0;
  r.oriented = r.misoriented_edges == 0;
  r.manifold = r.nonmanifold_edges == 0 && r.nonmanifold_vertices == 0;
  return r;
}

}  // namespace

TopologyReport check_topology(const PolygonMesh& m, std::size_t max_problems) {
  Loops L;
  L.n_slots = m.V.size();
  L.n_faces = static_cast<std::int64_t>(m.faces.size());
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    const auto& face = m.faces[f];
    L.add(face.outer.data(), face.outer.size(), static_cast<Index>(f));
    for (const auto& h : face.holes) {
      L.add(h.data(), h.size(), static_cast<Index>(f));
      ++L.n_holes;
    }
  }
  return analyse(L, max_problems);
}

EulerCounts euler_counts(const PolygonMesh& m) { return check_topology(m, 0).counts; }

namespace {

// The live, non-degenerate triangles of `m` as loops; degenerate ones into `pre`.
template <class Real>
Loops live_loops(const TriMesh<Real>& m, TopologyReport& pre, std::size_t max_problems) {
  Loops L;
  L.n_slots = m.vertex_slots();
  L.verts.reserve(3 * m.triangle_slots());
  L.start.reserve(m.triangle_slots() + 1);
  L.face_of.reserve(m.triangle_slots());
  for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) {
      add_problem(
          pre, max_problems,
          {TopologyProblem::Kind::kDegenerateFace, tri[0] == tri[1] ? tri[0] : tri[2], static_cast<Index>(t), 0});
      continue;
    }
    L.add(tri.data(), 3, static_cast<Index>(t));
    ++L.n_faces;
  }
  return L;
}

}  // namespace

template <class Real>
EulerCounts euler_counts(const TriMesh<Real>& m) {
  MeshStatistics stats;
  return stats.compute(m).topology;
}

template <class Real>
TopologyReport check_topology(const TriMesh<Real>& m, std::size_t max_problems) {
  TopologyReport pre;
  TopologyReport r = analyse(live_loops(m, pre, max_problems), max_problems);
  if (!pre.problems.empty()) {
    r.manifold = false;
    r.problems.insert(r.problems.begin(), pre.problems.begin(), pre.problems.end());
    if (r.problems.size() > max_problems) r.problems.resize(max_problems);
  }
  // A live vertex that no live triangle uses is an orphan: invalid for a closed solid.
  std::vector<std::uint8_t> used(m.vertex_slots(), 0);
  for (std::size_t t = 0; t < m.triangle_slots(); ++t)
    if (m.triangle_alive[t])
      for (Index v : m.triangle[t]) used[static_cast<std::size_t>(v)] = 1;
  for (std::size_t v = 0; v < m.vertex_slots(); ++v) {
    if (m.vertex_alive[v] && !used[v]) {
      ++r.orphan_vertices;
      add_problem(r, max_problems, {TopologyProblem::Kind::kOrphanVertex, static_cast<Index>(v), -1, 0});
    } else if (!m.vertex_alive[v] && used[v]) {
      ++r.dead_vertex_references;
      add_problem(r, max_problems, {TopologyProblem::Kind::kDeadVertexReference, static_cast<Index>(v), -1, 0});
    }
  }
  return r;
}

template <class Real>
std::pair<std::vector<Index>, Index> vertex_components(const TriMesh<Real>& m) {
  UnionFind uf(m.vertex_slots());
  std::vector<std::uint8_t> used(m.vertex_slots(), 0);
  for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    for (Index v : tri) used[static_cast<std::size_t>(v)] = 1;
    uf.unite(tri[0], tri[1]);
    uf.unite(tri[1], tri[2]);
  }
  std::vector<Index> id(m.vertex_slots(), -1);
  Index count = 0;
  for (std::size_t v = 0; v < m.vertex_slots(); ++v) {
    if (!used[v]) continue;
    const auto root = static_cast<std::size_t>(uf.find(static_cast<Index>(v)));
    if (id[root] < 0) id[root] = count++;
    id[v] = id[root];
  }
  return {std::move(id), count};
}

template EulerCounts euler_counts(const TriMesh<float>&);
template EulerCounts euler_counts(const TriMesh<double>&);
template TopologyReport check_topology(const TriMesh<float>&, std::size_t);
template TopologyReport check_topology(const TriMesh<double>&, std::size_t);
template std::pair<std::vector<Index>, Index> vertex_components(const TriMesh<float>&);
template std::pair<std::vector<Index>, Index> vertex_components(const TriMesh<double>&);

}  // namespace meltlab::sim
