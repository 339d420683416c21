// The harness's local topology repair, run after Alg. 3 on the vertices whose
// neighbourhood changed this cycle (the monograph's Alg. 2/3 do not keep a mesh manifold
// in every configuration: a collapse can merge two vertices that share more than the two
// neighbours of their edge, e.g. the last three-edge loop of a neck, and the single
// count-2 test of Alg. 3 misses glued pairs on a vertex that has other triangles too).
//
// For a vertex v, every triangle (v, x, y) contributes the directed link edge x -> y. On a
// closed, oriented 2-manifold the link is one directed cycle of length >= 3. Otherwise:
//   * a 2-cycle x -> y -> x is a glued pair (v, x, y), (v, y, x): both triangles go;
//   * several disjoint cycles: v is a pinch point where parts of the surface touch (a
//     neck that collapsed to a point): v is split into one vertex per cycle, which is how
//     the object separates into parts (S grows) or a handle breaks (G shrinks);
//   * a node with two or more outgoing link edges: edge (v, x) has more than two
//     triangles; it is collapsed (x merged into v, or v into x, keeping the smaller index
//     as Alg. 2 does), which turns it into one of the cases above.
// Every step deletes at least one element or removes a pinch, and touched neighbours are
// re-examined, so the worklist empties. Directed-edge balance (each edge used equally often
// in both directions) is preserved by merging, which guarantees the link decomposes into
// cycles. The common case (nothing to repair) costs one link test per dirty vertex.

#include "workspace.h"

#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <mutex>
#include <deque>
#include <unordered_map>
#include <unordered_set>

namespace meltlab::sim {

namespace {

struct LinkEdge {
  Index from, to, tri;
};

// Link of v from its triangles (each must contain v exactly once).
template <class Real>
void build_link(const TriMesh<Real>& m, Index v, const std::vector<Index>& tris, std::vector<LinkEdge>& link) {
  link.clear();
  for (Index t : tris) {
    const Triangle& tri = m.triangle[static_cast<std::size_t>(t)];
    const int k = tri[0] == v ? 0 : (tri[1] == v ? 1 : 2);
    link.push_back({tri[static_cast<std::size_t>((k + 1) % 3)], tri[static_cast<std::size_t>((k + 2) % 3)], t});
  }
}

// True if the link is a single directed cycle of length >= 3 (v is a manifold vertex).
bool link_is_single_cycle(std::vector<LinkEdge>& link) {
  const std::size_t k = link.size();
  if (k < 3) return false;
  std::sort(link.begin(), link.end(), [](const LinkEdge& a, const LinkEdge& b) { return a.from < b.from; });
  for (std::size_t i = 1; i < k; ++i)
    if (link[i].from == link[i - 1].from) return false;  // a node with two out-edges
  auto find_from = [&](Index x) -> std::ptrdiff_t {
    auto it = std::lower_bound(link.begin(), link.end(), x, [](const LinkEdge& e, Index val) { return e.from < val; });
    return (it != link.end() && it->from == x) ? it - link.begin() : -1;
  };
  std::size_t steps = 0;
  std::ptrdiff_t at = 0;
  do {
    at = find_from(link[static_cast<std::size_t>(at)].to);
    if (at < 0) return false;
    ++steps;
  } while (at != 0 && steps <= k);
  return at == 0 && steps == k;
}

template <class Real>
class Repairer {
 public:
  Repairer(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report) : m_(m), ws_(ws), report_(report) {}

  void run(const std::vector<Index>& start) {
    for (Index v : start) enqueue(v);
    const std::size_t cap = 64 * start.size() + 100000;
    std::size_t steps = 0;
    while (!queue_.empty()) {
      const Index v = queue_.front();
      queue_.pop_front();
      queued_.erase(v);
      if (++steps > cap)
        throw InvariantError(fmt::format("topology repair did not converge after {} steps (at vertex v{})", steps, v));
      process(v);
    }
  }

 private:
  std::vector<Index> live_triangles_of(Index v) const {
    std::vector<Index> out;
    for (Index t : ws_.adj.of(v)) {
      const auto ts = static_cast<std::size_t>(t);
      if (!m_.triangle_alive[ts]) continue;
      const Triangle& tri = m_.triangle[ts];
      if (tri[0] == v || tri[1] == v || tri[2] == v) out.push_back(t);
    }
    return out;
  }
  void enqueue(Index v) {
    if (queued_.insert(v).second) queue_.push_back(v);
  }
  void kill_triangle(Index t) {
    m_.triangle_alive[static_cast<std::size_t>(t)] = 0;
    for (Index c : m_.triangle[static_cast<std::size_t>(t)]) {
      ws_.adj.erase(c, t);
      enqueue(c);
    }
  }

  void process(Index v) {
    const auto vs = static_cast<std::size_t>(v);
    if (!m_.vertex_alive[vs]) return;
    const std::vector<Index> tris = live_triangles_of(v);
    m_.triangle_count[vs] = static_cast<Index>(tris.size());
    if (tris.empty()) {
      m_.vertex_alive[vs] = 0;
      ++report_.orphan_vertices;
      return;
    }
    build_link(m_, v, tris, link_);
    std::vector<LinkEdge> sorted = link_;
    if (link_is_single_cycle(sorted)) return;

    // (1) glued pairs: x -> y and y -> x.
    std::sort(link_.begin(), link_.end(), [](const LinkEdge& a, const LinkEdge& b) {
      return a.from != b.from ? a.from < b.from : (a.to != b.to ? a.to < b.to : a.tri < b.tri);
    });
    std::vector<std::uint8_t> used(link_.size(), 0);
    bool removed = false;
    for (std::size_t i = 0; i < link_.size(); ++i) {
      if (used[i]) continue;
      for (std::size_t j = 0; j < link_.size(); ++j) {
        if (j == i || used[j]) continue;
        if (link_[j].from == link_[i].to && link_[j].to == link_[i].from) {
          used[i] = used[j] = 1;
          kill_triangle(link_[i].tri);
          kill_triangle(link_[j].tri);
          ++report_.repair_glued_pairs;
          removed = true;
          break;
        }
      }
    }
    if (removed) {
      enqueue(v);
      return;
    }

    // (2) a node with several out-edges: non-manifold edge (v, x) -> collapse it.
    for (std::size_t i = 1; i < link_.size(); ++i) {
      if (link_[i].from == link_[i - 1].from) {
        collapse_edge(v, link_[i].from);
        return;
      }
    }

    // (3) every node has one out-edge (and, by balance, one in-edge): disjoint cycles.
    std::vector<std::vector<Index>> cycles;
    std::vector<std::uint8_t> seen(link_.size(), 0);
    auto index_of_from = [&](Index x) -> std::ptrdiff_t {
      auto it =
          std::lower_bound(link_.begin(), link_.end(), x, [](const LinkEdge& e, Index val) { return e.from < val; });
      return (it != link_.end() && it->from == x) ? it - link_.begin() : -1;
    };
    for (std::size_t s = 0; s < link_.size(); ++s) {
      if (seen[s]) continue;
      std::vector<Index> cyc;
      std::ptrdiff_t at = static_cast<std::ptrdiff_t>(s);
      while (at >= 0 && !seen[static_cast<std::size_t>(at)]) {
        seen[static_cast<std::size_t>(at)] = 1;
        cyc.push_back(link_[static_cast<std::size_t>(at)].tri);
        at = index_of_from(link_[static_cast<std::size_t>(at)].to);
      }
      if (at < 0)
        throw InvariantError(fmt::format("vertex v{}: open link (a boundary edge) during topology repair", v));
      std::sort(cyc.begin(), cyc.end());
      cycles.push_back(std::move(cyc));
    }
    // The cycle holding v's smallest triangle keeps v; each other gets a new vertex.
    std::sort(cycles.begin(), cycles.end(), [](const auto& a, const auto& b) { return a.front() < b.front(); });
    ws_.adj.assign(v, cycles[0]);
    for (std::size_t c = 1; c < cycles.size(); ++c) {
      const Vec3<Real> p = m_.position[vs];
      const Vec3<Real> n = m_.normal[vs];
      const Index u = m_.add_vertex(p);
      m_.normal.set(static_cast<std::size_t>(u), n);
      m_.triangle_count[static_cast<std::size_t>(u)] = static_cast<Index>(cycles[c].size());
      for (Index t : cycles[c]) {
        Triangle& tri = m_.triangle[static_cast<std::size_t>(t)];
        for (Index& x : tri)
          if (x == v) x = u;
        tri = rotate_min_first(tri);
      }
      ws_.adj.grow(m_.vertex_slots());
      ws_.adj.assign(u, cycles[c]);
      ++report_.repair_vertex_splits;
    }
    m_.triangle_count[vs] = static_cast<Index>(cycles[0].size());
  }

  void collapse_edge(Index v, Index x) {
    const Index keep = std::min(v, x), gone = std::max(v, x);
    const auto ks = static_cast<std::size_t>(keep), gs = static_cast<std::size_t>(gone);
    const std::vector<Index> tg = live_triangles_of(gone);
    m_.position.set(ks, (m_.position[ks] + m_.position[gs]) / Real(2));
    m_.vertex_alive[gs] = 0;
    m_.reindex[gs] = keep;
    ws_.reindex_changed.push_back(gone);
    std::vector<Index> moved;
    for (Index t : tg) {
      Triangle& tri = m_.triangle[static_cast<std::size_t>(t)];
      for (Index& y : tri)
        if (y == gone) y = keep;
      if (is_degenerate(tri)) {
        kill_triangle(t);
      } else {
        tri = rotate_min_first(tri);
        moved.push_back(t);
        for (Index c : tri) enqueue(c);
      }
    }
    std::vector<Index> kl = live_triangles_of(keep);
    for (Index t : kl) enqueue_corners(t);
    std::vector<Index> all;
    std::set_union(kl.begin(), kl.end(), moved.begin(), moved.end(), std::back_inserter(all));
    ws_.adj.assign(keep, all);
    ws_.adj.assign(gone, {});
    enqueue(keep);
    ++report_.repair_edge_collapses;
  }
  void enqueue_corners(Index t) {
    for (Index c : m_.triangle[static_cast<std::size_t>(t)]) enqueue(c);
  }

  TriMesh<Real>& m_;
  MeltWorkspace& ws_;
  CycleReport& report_;
  std::deque<Index> queue_;
  std::unordered_set<Index> queued_;
  std::vector<LinkEdge> link_;
};

}  // namespace

template <class Real>
void repair_pass(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report, Execution exec) {
  prepare_workspace(ws, m);
  // Cheap check first: one link test per dirty vertex; the repair machinery runs only if
  // some vertex is not manifold. The tests only read the mesh (an orphan clears its own
  // flag), so chunks of the dirty list run side by side; `bad` is sorted afterwards, so the
  // repair sees the same list whatever the split. A test costs ~0.2 µs (a few cache misses),
  // so chunks of kCheckGrain vertices are ~0.1 ms.
  constexpr std::size_t kCheckGrain = 512;
  std::vector<Index> bad;
  std::atomic<std::int64_t> orphans{0};
  std::mutex bad_mutex;
  const std::vector<Index>& dirty = ws.dirty_list;
  for_range(
      exec, dirty.size(),
      [&](std::size_t begin, std::size_t end) {
        std::vector<Index> tris, local_bad;
        std::vector<LinkEdge> link;
        std::int64_t local_orphans = 0;
        for (std::size_t i = begin; i < end; ++i) {
          const Index v = dirty[i];
          const auto vs = static_cast<std::size_t>(v);
          if (!m.vertex_alive[vs]) continue;
          const auto list = ws.adj.of(v);
          if (list.empty()) {
            m.vertex_alive[vs] = 0;
            ++local_orphans;
            continue;
          }
          tris.assign(list.begin(), list.end());
          build_link(m, v, tris, link);
          if (!link_is_single_cycle(link)) local_bad.push_back(v);
        }
        orphans.fetch_add(local_orphans, std::memory_order_relaxed);
        if (!local_bad.empty()) {
          const std::lock_guard<std::mutex> lock(bad_mutex);
          bad.insert(bad.end(), local_bad.begin(), local_bad.end());
        }
      },
      kCheckGrain);
  report.orphan_vertices += orphans.load();
  if (!bad.empty()) {
    std::sort(bad.begin(), bad.end());
    Repairer<Real> repairer(m, ws, report);
    repairer.run(bad);
    prepare_workspace(ws, m);
    ws.schedule.invalidate();
    ws.packed_valid = false;
  }
  for (Index v : ws.dirty_list)
    if (m.vertex_alive[static_cast<std::size_t>(v)])
      m.triangle_count[static_cast<std::size_t>(v)] = static_cast<Index>(ws.adj.of(v).size());
}

template <class Real>
CycleReport repair_topology(TriMesh<Real>& m, const std::vector<Index>& vertices) {
  MeltWorkspace ws;
  prepare_workspace(ws, m);
  for (Index v : vertices) ws.mark_dirty(v);
  CycleReport report;
  repair_pass(m, ws, report, Execution::kSerial);
  return report;
}

template void repair_pass(TriMesh<float>&, MeltWorkspace&, CycleReport&, Execution);
template void repair_pass(TriMesh<double>&, MeltWorkspace&, CycleReport&, Execution);
template CycleReport repair_topology(TriMesh<float>&, const std::vector<Index>&);
template CycleReport repair_topology(TriMesh<double>&, const std::vector<Index>&);

}  // namespace meltlab::sim
