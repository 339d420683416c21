#include <meltlab/sim/mesh_stats.h>

#include "union_find.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace meltlab::sim {

namespace {

// Grain of the parallel loops: a few thousand triangles or edge lists amortise a task.
constexpr std::size_t kGrain = 2048;

struct Box {
  Vec3<double> lo = Vec3<double>::Constant(std::numeric_limits<double>::infinity());
  Vec3<double> hi = Vec3<double>::Constant(-std::numeric_limits<double>::infinity());
  void join(const Box& o) {
    lo = lo.cwiseMin(o.lo);
    hi = hi.cwiseMax(o.hi);
  }
};

bool degenerate(const Triangle& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

}  // namespace

template <class Real>
const MeshStats& MeshStatistics::compute(const TriMesh<Real>& m) {
  const std::size_t nt = m.triangle_slots(), nv = m.vertex_slots();
  stats_ = MeshStats{};
  QualityReport& r = stats_.quality;
  EulerCounts& c = stats_.topology;

  // 1. The measures of each live triangle, in parallel: each slot is written by one task, and
  //    the bounding box (min and max are exact in any order) joined across tasks.
  tri_.resize(nt);
  const Box box = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nt, kGrain), Box{},
      [&](const tbb::blocked_range<std::size_t>& range, Box b) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
          if (!m.triangle_alive[t]) continue;
          const Triangle& tri = m.triangle[t];
          Vec3<double> p[3];
          for (int k = 0; k < 3; ++k) {
            p[k] = m.position[static_cast<std::size_t>(tri[static_cast<std::size_t>(k)])].template cast<double>();
            b.lo = b.lo.cwiseMin(p[k]);
            b.hi = b.hi.cwiseMax(p[k]);
          }
          TriangleTerms& T = tri_[t];
          const Vec3<double> n = (p[1] - p[0]).cross(p[2] - p[0]);
          T.half_area = 0.5 * n.norm();
          T.six_volume = p[0].dot(p[1].cross(p[2]));
          T.unit_normal = n.squaredNorm() > 0 ? Vec3<double>(n.normalized()) : Vec3<double>::Zero();
          T.twist_deg = triangle_twist_deg(p[0], p[1], p[2]);
          T.quality = triangle_quality(T.half_area, p[0], p[1], p[2]);
        }
        return b;
      },
      [](Box a, const Box& b) {
        a.join(b);
        return a;
      });

  // 2. Their sums in slot order (one thread), and the uses of each edge counted under its
  //    smaller vertex.
  double sum_s = 0, sum_q = 0, six_v = 0;
  std::int64_t nf = 0;
  r.min_q = 1.0;
  start_.assign(nv + 1, 0);
  for (std::size_t t = 0; t < nt; ++t) {
    if (!m.triangle_alive[t]) continue;
    const TriangleTerms& T = tri_[t];
    r.area += T.half_area;
    six_v += T.six_volume;
    sum_s += T.twist_deg;
    sum_q += T.quality;
    r.min_q = std::min(r.min_q, T.quality);
    ++nf;
    const Triangle& tri = m.triangle[t];
    for (int k = 0; k < 3; ++k)
      ++start_[static_cast<std::size_t>(std::min(tri[static_cast<std::size_t>(k)], tri[(k + 1) % 3])) + 1];
  }
  r.volume = six_v / 6.0;
  if (nf > 0) {
    r.bbox_min = box.lo;
    r.bbox_max = box.hi;
    r.Qs = sum_s / static_cast<double>(nf);
    r.Qq = sum_q / static_cast<double>(nf);
  } else {
    r.min_q = 0;
  }

  // 3. File the uses under lo in triangle order (so each list is stable), and the Euler counts'
  //    per-slot sums: +1 for a used vertex, +1 for a face at its first vertex, -1 for an edge
  //    at lo (added to the component roots once the unions are done).
  for (std::size_t v = 0; v < nv; ++v) start_[v + 1] += start_[v];
  use_.resize(start_[nv]);
  used_.assign(nv, 0);
  comp_sum_.assign(nv, 0);
  for (std::size_t t = 0; t < nt; ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    const bool topo = !degenerate(tri);
    if (topo) {
      ++c.F;
      comp_sum_[static_cast<std::size_t>(tri[0])] += 1;
      for (Index v : tri) used_[static_cast<std::size_t>(v)] = 1;
    }
    for (int k = 0; k < 3; ++k) {
      const Index u = tri[static_cast<std::size_t>(k)], w = tri[(k + 1) % 3];
      const auto lo = static_cast<std::size_t>(std::min(u, w));
      use_[start_[lo]++] = {std::max(u, w), topo ? static_cast<Index>(t) : ~static_cast<Index>(t)};
    }
  }
  for (std::size_t v = nv; v > 0; --v) start_[v] = start_[v - 1];
  start_[0] = 0;

  // 4. Each list sorted by hi (stable: a few uses per vertex), and each edge's length and, for
  //    an edge of two uses, the dihedral measure, at the edge's first use; in parallel.
  edge_.resize(use_.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t lo = range.begin(); lo != range.end(); ++lo) {
      const std::size_t b = start_[lo], e = start_[lo + 1];
      for (std::size_t i = b + 1; i < e; ++i) {
        const EdgeUse x = use_[i];
        std::size_t j = i;
        for (; j > b && use_[j - 1].hi > x.hi; --j) use_[j] = use_[j - 1];
        use_[j] = x;
      }
      const Vec3<double> p_lo = m.position[lo].template cast<double>();
      for (std::size_t i = b; i < e;) {
        std::size_t j = i + 1;
        while (j < e && use_[j].hi == use_[i].hi) ++j;
        EdgeTerms& E = edge_[i];
        E.length = (p_lo - m.position[static_cast<std::size_t>(use_[i].hi)].template cast<double>()).norm();
        if (j - i == 2) {
          const auto ta = static_cast<std::size_t>(use_[i].tri >= 0 ? use_[i].tri : ~use_[i].tri);
          const auto tb = static_cast<std::size_t>(use_[i + 1].tri >= 0 ? use_[i + 1].tri : ~use_[i + 1].tri);
          E.dihedral_deg = dihedral_deg(tri_[ta].unit_normal, tri_[tb].unit_normal);
        }
        i = j;
      }
    }
  });

  // 5. The edges in (lo, hi) order (one thread): the sums of the quality measures, and the
  //    edges and unions of the Euler counts (edges some non-degenerate triangle uses).
  UnionFind uf;
  uf.parent.swap(parent_);
  uf.reset(nv);
  double sum_d = 0, sum_len = 0;
  std::int64_t n_len = 0;
  for (std::size_t lo = 0; lo < nv; ++lo) {
    const std::size_t e = start_[lo + 1];
    for (std::size_t i = start_[lo]; i < e;) {
      std::size_t j = i + 1;
      bool topo = use_[i].tri >= 0;
      for (; j < e && use_[j].hi == use_[i].hi; ++j) topo = topo || use_[j].tri >= 0;
      sum_len += edge_[i].length;
      ++n_len;
      if (j - i == 2) {
        sum_d += edge_[i].dihedral_deg;
        r.max_d = std::max(r.max_d, edge_[i].dihedral_deg);
        ++r.edges;
      }
      if (topo) {
        ++c.E;
        comp_sum_[lo] -= 1;
        uf.unite(static_cast<Index>(lo), use_[i].hi);
      }
      i = j;
    }
  }
  if (nf > 0) {
    r.Qd = r.edges > 0 ? sum_d / static_cast<double>(r.edges) : 0.0;
    r.mean_edge_length = n_len > 0 ? sum_len / static_cast<double>(n_len) : 0.0;
  }

  // 6. The per-slot sums into their roots (a root is its set's smallest slot, so it comes
  //    first), then S, G and chi.
  for (std::size_t v = 0; v < nv; ++v) {
    if (!used_[v]) continue;
    ++c.V;
    comp_sum_[v] += 1;
    const auto root = static_cast<std::size_t>(uf.find(static_cast<Index>(v)));
    if (root != v) {
      comp_sum_[root] += comp_sum_[v];
      comp_sum_[v] = 0;
    }
  }
  finish_euler_counts(used_, uf, comp_sum_, c);
  parent_.swap(uf.parent);
  return stats_;
}

template const MeshStats& MeshStatistics::compute(const TriMesh<float>&);
template const MeshStats& MeshStatistics::compute(const TriMesh<double>&);

}  // namespace meltlab::sim
