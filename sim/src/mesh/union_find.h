#pragma once
// Private to sim/src: union-find over vertex slots (the topology check, the per-cycle
// statistics and the melt cycle's remnant check), and the Euler counts of §2.3 from the
// per-component sums that the topology check and the per-cycle statistics both collect.

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/topology.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace meltlab::sim {

/// Union-find whose root is always the smallest index of its set (a node's parent is never larger
/// than the node: unite hangs larger under smaller), so the roots do not depend on the order of
/// the unions.
struct UnionFind {
  std::vector<Index> parent;
  UnionFind() = default;
  explicit UnionFind(std::size_t n) { reset(n); }
  void reset(std::size_t n) {
    parent.resize(n);
    std::iota(parent.begin(), parent.end(), 0);
  }
  Index find(Index x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      auto& p = parent[static_cast<std::size_t>(x)];
      p = parent[static_cast<std::size_t>(p)];
      x = p;
    }
    return x;
  }
  /// Joins the sets of x and y (any members) by Rem's algorithm with splicing: both are walked
  /// up together, the one with the larger parent first, and each step moves that node's parent
  /// to the other's (smaller) parent. Every node's parent stays no larger than the node, so each
  /// root is its set's smallest index; the sets and, after flatten(), the parents are the same as
  /// any other sequence of unions of the same pairs gives. (Against finding both roots and hanging
  /// the larger under the smaller: 1.4-1.7x faster in the remnant check, docs/melt-core.md, issue 20
  /// step 30.)
  void unite(Index x, Index y) {
    Index* const p = parent.data();
    auto at = [p](Index v) -> Index& { return p[static_cast<std::size_t>(v)]; };
    while (at(x) != at(y)) {
      if (at(x) < at(y)) std::swap(x, y);
      if (at(x) == x) {  // x is a root: hang it below y's parent
        at(x) = at(y);
        return;
      }
      const Index z = at(x);
      at(x) = at(y);
      x = z;
    }
  }
  /// Points every slot straight at its root: every link goes to a smaller index, so one
  /// ascending pass does it. Afterwards parent[v] is v's root.
  void flatten() {
    for (std::size_t v = 0; v < parent.size(); ++v) parent[v] = parent[static_cast<std::size_t>(parent[v])];
  }
};

/// S, G, chi and genus_valid of `c` (V, E, F, H already set) from `comp_sum`, which holds at
/// each component's root its V - E + F - H (2 - 2G for a closed orientable component).
/// `used` marks the vertex slots that some face uses.
inline void finish_euler_counts(const std::vector<std::uint8_t>& used, UnionFind& uf,
                                const std::vector<std::int64_t>& comp_sum, EulerCounts& c) {
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (!used[v] || uf.find(static_cast<Index>(v)) != static_cast<Index>(v)) continue;
    ++c.S;
    const std::int64_t x = comp_sum[v];
    if ((x % 2) != 0 || x > 2) c.genus_valid = false;  // G truncated; chi below shows it
    c.G += (2 - x) / 2;
  }
  c.chi = c.V - c.E + c.F - c.H - 2 * (c.S - c.G);
  if (c.chi != 0) c.genus_valid = false;
}

}  // namespace meltlab::sim
