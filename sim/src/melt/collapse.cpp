// Alg. 2: short-edge collapse (monograph §3.2, Eq. 3.7, Fig. 3.6, Fig. 3.11).
//
// Mark (one sweep over the triangles): each live triangle (a, b, c), a the smallest index,
// tests its edges in the order ab, bc, ca and marks at most one (if/else-if, as in the
// monograph): the higher index of a short edge is to be merged into the lower one. Several
// triangles may mark one vertex with different targets (`reindex_conflict_policy`): the
// smallest target wins, which does not depend on the order the triangles are visited in,
// so serial and parallel runs mark identically.
// Flatten: targets are always smaller indices, so an ascending sweep resolves every chain
// in O(n) (root[k] = root[target[k]], target[k] < k; Fig. 3.11).
// Merge (`merge_position_mode`): cluster mean (GPU §5.4, default) or the CPU's sequential
// pairwise mean; both take a cluster's members in ascending index order.
// Re-point: only the triangles of merged vertices change; they are re-pointed to the
// roots, deleted if degenerate, and rotated min-index first (Alg. 3's sort, applied where
// indices changed). Every vertex whose triangles changed is marked dirty for Alg. 3 and the
// repair.

#include "workspace.h"

#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

namespace meltlab::sim {

std::vector<Index> flatten_merge_targets(const std::vector<Index>& target) {
  for (std::size_t v = 0; v < target.size(); ++v)
    if (target[v] < 0 || target[v] > static_cast<Index>(v))
      throw InvariantError(fmt::format("merge target of v{} is v{}; targets must not exceed the index", v, target[v]));
  // root[k] = end of k's chain: targets are smaller indices, so ascending order resolves them.
  std::vector<Index> root(target.size());
  for (std::size_t v = 0; v < target.size(); ++v) {
    const Index t = target[v];
    root[v] = t == static_cast<Index>(v) ? t : root[static_cast<std::size_t>(t)];
  }
  return root;
}

namespace {

// Mark: every vertex's merge target (m.reindex, itself if none) from the short edges of the
// live triangles. Triangles whose shortest edge before this cycle's moves, less what the moves
// can shorten it, is still above kr are skipped (see MeltWorkspace::min_edge2); the others are
// tested exactly. Returns whether anything was marked.
template <class Real>
bool mark_short_edges(TriMesh<Real>& m, double kr, Execution exec, MeltWorkspace& ws) {
  const std::size_t nv = m.vertex_slots();
  const std::size_t nt = m.triangle_slots();
  const auto kr2 = static_cast<Real>(kr * kr);
  std::vector<Index>& target = m.reindex;
  // Every target back to itself: only the entries the last cycle changed, where those are known.
  if (ws.reindex_tracked) {
    for (Index v : ws.reindex_changed) target[static_cast<std::size_t>(v)] = v;
  } else {
    for (std::size_t v = 0; v < nv; ++v) target[v] = static_cast<Index>(v);
  }
  ws.reindex_changed.clear();
  ws.reindex_tracked = true;
  ws.merged.clear();
  std::mutex merged_mutex;
  // The keys were computed in Real from the positions before the moves (relative error a few
  // eps of Real, as the exact test's) and rounded down to float; the margin of 64 float eps
  // covers these and the rounding of the bound. Below the smallest normal float the rounding
  // is not relative: there (kr and the moves that small) every triangle is tested.
  const std::vector<float>& min_edge2 = ws.min_edge2;
  constexpr double kFloatEps = std::numeric_limits<float>::epsilon();
  constexpr double kFloatMin = std::numeric_limits<float>::min(), kFloatMax = std::numeric_limits<float>::max();
  const double reach = (kr + 2.0 * ws.cycle_move_bound) * (1.0 + 64.0 * kFloatEps);
  const bool keys = ws.min_edge2_current && min_edge2.size() == nt && reach * reach >= 4.0 * kFloatMin &&
                    reach * reach < 0.5 * kFloatMax;
  ws.min_edge2_current = false;
  // Rounded up to float, so that key > skip_above implies key > reach² exactly.
  const float skip_above =
      keys ? std::nextafter(static_cast<float>(reach * reach), std::numeric_limits<float>::infinity()) : 0.0f;
  const bool parallel = exec == Execution::kParallel;
  const float* const key = keys ? min_edge2.data() : nullptr;  // locals: the stores below cannot alias them
  const std::uint8_t* const alive = m.triangle_alive.data();
  // Corners are read from the packed copy of the positions (the same numbers as the columns;
  // one cache line per corner instead of three, and the copy the next deformation gathers
  // from stays in the cache). It is made current here if a repair or compaction cleared it.
  std::vector<Real>& packed_positions = ws.packed_positions<Real>();
  if (!ws.packed_valid || packed_positions.size() != 3 * nv + 1) {
    pack_positions(m, packed_positions);
    ws.packed_valid = true;
  }
  const Real* const packed = packed_positions.data();
  auto corner = [packed](Index v) {
    const Real* p = packed + 3 * static_cast<std::size_t>(v);
    return Vec3<Real>(p[0], p[1], p[2]);
  };
  // The exact test of triangle t (after the moves); a vertex that gets its first target this
  // cycle joins `newly` (in parallel: the thread whose exchange replaced the vertex itself).
  auto test = [&m, &target, corner, kr2, parallel](std::size_t t, std::vector<Index>& newly) {
    const Triangle& tri = m.triangle[t];
    const Vec3<Real> pa = corner(tri[0]), pb = corner(tri[1]), pc = corner(tri[2]);
    const Vec3<Real> ab = pb - pa, bc = pc - pb, ca = pa - pc;
    const Real l2[3] = {ab.x() * ab.x() + ab.y() * ab.y() + ab.z() * ab.z(),
                        bc.x() * bc.x() + bc.y() * bc.y() + bc.z() * bc.z(),
                        ca.x() * ca.x() + ca.y() * ca.y() + ca.z() * ca.z()};
    Index from, to;
    if (l2[0] < kr2) {
      from = tri[1], to = tri[0];
    } else if (l2[1] < kr2) {
      from = std::max(tri[1], tri[2]), to = std::min(tri[1], tri[2]);
    } else if (l2[2] < kr2) {
      from = tri[2], to = tri[0];
    } else {
      return;
    }
    Index& slot = target[static_cast<std::size_t>(from)];
    if (parallel) {
      // to < from: the loop ends with `before` the value it replaced, or one already <= to.
      std::atomic_ref<Index> ref(slot);
      Index before = ref.load(std::memory_order_relaxed);
      while (to < before && !ref.compare_exchange_weak(before, to, std::memory_order_relaxed)) {
      }
      if (before == from) newly.push_back(from);
    } else if (to < slot) {
      if (slot == from) newly.push_back(from);
      slot = to;
    }
  };
  auto mark_range = [&, key, alive, skip_above](std::size_t begin, std::size_t end) {
    std::vector<Index> newly;
    auto publish = [&] {
      if (newly.empty()) return;
      const std::lock_guard<std::mutex> lock(merged_mutex);
      ws.merged.insert(ws.merged.end(), newly.begin(), newly.end());
    };
    if (!key) {
      for (std::size_t t = begin; t < end; ++t)
        if (alive[t]) test(t, newly);
      publish();
      return;
    }
    // In chunks: list the triangles whose keys do not rule them out (most are ruled out, eight
    // keys at once), then test them with their corners prefetched kAhead candidates ahead. The
    // candidates are few and scattered, so testing each as the scan finds it waited for its
    // corners one candidate at a time (the 871k dragon: ~80k candidates per cycle, their corners
    // mostly out of the cache after the sweep).
    constexpr std::size_t kChunk = 1024, kAhead = 8;
    Index candidate[kChunk + kLanes];  // room for a whole group's indices past the last candidate
    for (std::size_t chunk = begin; chunk < end; chunk += kChunk) {
      const std::size_t chunk_end = std::min(end, chunk + kChunk);
      std::size_t n = 0;
      for (std::size_t t = chunk; t < chunk_end;) {
        if (t % kLanes == 0 && t + kLanes <= chunk_end) {
          // Eight keys and flags at once, the candidates taken from the bits of the comparison: a
          // branch per triangle, taken at random where candidates are dense, was half of this pass
          // on the 871k dragon (docs/melt-core.md, issue 20 step 28).
          unsigned bits = ~lane_bits<float>(load_lanes(key + t) > skip_above) & 0xffu;
          if (bits != 0)
            n += append_bit_indices(bits & lane_bits<float>(lanes_nonzero<float>(alive + t)), static_cast<Index>(t),
                                    candidate + n);
          t += kLanes;
          continue;
        }
        if (!(key[t] > skip_above) && alive[t]) candidate[n++] = static_cast<Index>(t);
        ++t;
      }
      // Each candidate's triangle record asked for 2 kAhead candidates ahead, its corners kAhead ahead.
      for (std::size_t i = 0; i < std::min(n, 2 * kAhead); ++i)
        __builtin_prefetch(&m.triangle[static_cast<std::size_t>(candidate[i])]);
      for (std::size_t i = 0; i < n; ++i) {
        if (i + 2 * kAhead < n) __builtin_prefetch(&m.triangle[static_cast<std::size_t>(candidate[i + 2 * kAhead])]);
        if (i + kAhead < n)
          for (Index v : m.triangle[static_cast<std::size_t>(candidate[i + kAhead])]) {
            const Real* p = packed + 3 * static_cast<std::size_t>(v);
            __builtin_prefetch(p);
            __builtin_prefetch(p + 2);
          }
        test(static_cast<std::size_t>(candidate[i]), newly);
      }
    }
    publish();
  };
  for_range(exec, nt, mark_range);
  std::sort(ws.merged.begin(), ws.merged.end());
  return !ws.merged.empty();
}

// Flatten chains (ws.root, and m.reindex = the monograph's i after flattening) of the merged
// vertices (ws.merged, ascending: those the short-edge test marked). Their targets are smaller indices,
// so in ascending order each one's target already has its final root (Fig. 3.11), and every
// unmarked vertex is its own root (ws.root is the identity outside them). The same roots as
// flatten_merge_targets over every vertex.
template <class Real>
void flatten_and_list_merged(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report) {
  std::vector<Index>& target = m.reindex;
  std::vector<Index>& root = ws.root;
  for (Index v : ws.merged) {
    const auto vs = static_cast<std::size_t>(v);
    root[vs] = root[static_cast<std::size_t>(target[vs])];
    target[vs] = root[vs];
  }
  report.merged_vertices += static_cast<std::int64_t>(ws.merged.size());
  ws.reindex_changed.assign(ws.merged.begin(), ws.merged.end());
}

// Merge positions into the roots, members in ascending order (ws.touched_roots: the roots).
template <class Real>
void merge_positions(TriMesh<Real>& m, MergeMode merge, MeltWorkspace& ws) {
  const std::vector<Index>& root = ws.root;
  ws.touched_roots.clear();
  for (Index k : ws.merged) {
    const auto ks = static_cast<std::size_t>(k);
    const auto r = static_cast<std::size_t>(root[ks]);
    if (ws.cluster_size[r] == 0) {
      ws.touched_roots.push_back(static_cast<Index>(r));
      ws.cluster_size[r] = 1;
    }
    ++ws.cluster_size[r];
    if (merge == MergeMode::kSequentialPairwise)
      m.position.set(r, (m.position[ks] + m.position[r]) / Real(2));
    else
      m.position.set(r, m.position[r] + m.position[ks]);
    m.vertex_alive[ks] = 0;
  }
  std::vector<Real>& packed = ws.packed_positions<Real>();
  const bool keep_packed = ws.packed_valid && packed.size() == 3 * m.vertex_slots() + 1;
  for (Index r : ws.touched_roots) {
    const auto rs = static_cast<std::size_t>(r);
    auto& size = ws.cluster_size[rs];
    if (merge == MergeMode::kClusterMean) m.position.set(rs, m.position[rs] / static_cast<Real>(size));
    size = 0;
    if (keep_packed) {
      const Vec3<Real> p = m.position[rs];
      packed[3 * rs] = p.x(), packed[3 * rs + 1] = p.y(), packed[3 * rs + 2] = p.z();
    }
  }
}

// Re-point the triangles of merged vertices (ws.affected) to the roots: degenerate ones die,
// the others are rotated min-index first; their vertices are marked dirty.
template <class Real>
void repoint_triangles(TriMesh<Real>& m, MeltWorkspace& ws, CycleReport& report) {
  const std::vector<Index>& root = ws.root;
  std::vector<Index>& affected = ws.affected;
  affected.clear();
  const VertexTriangles& adj = ws.adj;
  prefetched_for_each(
      ws.merged, [&](Index k) { adj.prefetch_record(k); }, [&](Index k) { adj.prefetch_list(k); },
      [&](Index k) {
        for (Index t : adj.of(k)) affected.push_back(t);
      });
  std::sort(affected.begin(), affected.end());
  affected.erase(std::unique(affected.begin(), affected.end()), affected.end());
  std::int64_t degenerate = 0;
  prefetched_for_each(
      affected, [&](Index t) { __builtin_prefetch(&m.triangle[static_cast<std::size_t>(t)]); },
      [&](Index t) {
        for (Index v : m.triangle[static_cast<std::size_t>(t)]) {
          __builtin_prefetch(&root[static_cast<std::size_t>(v)]);
          __builtin_prefetch(&ws.dirty[static_cast<std::size_t>(v)]);
        }
      },
      [&](Index t) {
        const auto ts = static_cast<std::size_t>(t);
        Triangle& tri = m.triangle[ts];
        for (Index& v : tri) {
          v = root[static_cast<std::size_t>(v)];
          ws.mark_dirty(v);
        }
        if (is_degenerate(tri)) {
          m.triangle_alive[ts] = 0;
          ++degenerate;
        } else {
          tri = rotate_min_first(tri);
        }
      });
  report.degenerate_triangles += degenerate;
}

// Update the triangle lists: roots take their members' triangles, and the triangles that died
// in the re-pointing leave the lists of their corners. Every other entry stays right: a
// re-pointed triangle that lives still has each listed vertex as a corner (an unmerged corner
// keeps its index, a merged one is replaced by its root, which takes its list), so the lists
// come out as the live triangles of each vertex without re-reading the triangles of every
// vertex that a re-pointing touched (the 871k dragon: ~10k such vertices per cycle, each a few
// cache misses).
template <class Real>
void update_triangle_lists(TriMesh<Real>& m, MeltWorkspace& ws) {
  VertexTriangles& adj = ws.adj;
  const std::vector<Index>& root = ws.root;
  prefetched_for_each(
      ws.merged,
      [&](Index k) {
        adj.prefetch_record(k);
        adj.prefetch_record(root[static_cast<std::size_t>(k)]);
      },
      [&](Index k) {
        adj.prefetch_list(k);
        adj.prefetch_list(root[static_cast<std::size_t>(k)]);
      },
      [&](Index k) {
        const Index r = root[static_cast<std::size_t>(k)];
        // Append k's triangles to r's list (sorted merge, duplicates removed), then drop k's.
        std::vector<Index>& merged_list = ws.scratch;
        merged_list.clear();
        const auto a = adj.of(r);
        const auto b = adj.of(k);
        std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(merged_list));
        adj.assign(r, merged_list);
        adj.assign(k, {});
      });
  const std::uint8_t* const alive = m.triangle_alive.data();
  prefetched_for_each(
      ws.affected, [&](Index t) { __builtin_prefetch(alive + t); },
      [&](Index t) {
        if (!alive[t])
          for (Index v : m.triangle[static_cast<std::size_t>(t)]) adj.prefetch_record(v);
      },
      [&](Index t) {
        if (alive[t]) return;
        for (Index v : m.triangle[static_cast<std::size_t>(t)])
          adj.erase(v, t);  // a repeated corner: the second finds nothing
      });
}

}  // namespace

template <class Real>
void collapse_pass(TriMesh<Real>& m, double kr, MergeMode merge, Execution exec, MeltWorkspace& ws,
                   CycleReport& report) {
  prepare_workspace(ws, m);
  if (!mark_short_edges(m, kr, exec, ws)) return;
  flatten_and_list_merged(m, ws, report);
  merge_positions(m, merge, ws);
  repoint_triangles(m, ws, report);
  update_triangle_lists(m, ws);
  for (Index v : ws.merged) ws.root[static_cast<std::size_t>(v)] = v;  // the identity again
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
