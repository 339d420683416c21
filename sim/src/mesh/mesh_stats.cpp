#include <meltlab/sim/mesh_stats.h>

#include "../melt/lanes.h"
#include "union_find.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace meltlab::sim {

namespace {

// Grain of the parallel loops: a few thousand triangles or edge lists amortise a task.
constexpr std::size_t kGrain = 2048;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

bool degenerate(const Triangle& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; }

using L = Lanes<double>;

/// Eigen's order for a three-term dot product: (x + y) + z.
L dot3(const L (&u)[3], const L (&v)[3]) { return (u[0] * v[0] + u[1] * v[1]) + u[2] * v[2]; }

/// std::clamp(c, -1.0, 1.0), lane by lane (quality.cpp's cosine).
L clamp_unit(L c) {
  return lane_select<double>(c < -1.0, broadcast(-1.0), lane_select<double>(1.0 < c, broadcast(1.0), c));
}

}  // namespace

// The measures of the live triangles among slots [begin, end), end - begin <= kLanes, on eight
// lanes: the operations of the scalar definitions in the same order (Eigen's: sums of three
// terms as (x + y) + z, cross products as y z' - z y' ..., normalized() as v / sqrt(|v|²) where
// |v|² > 0; quality.cpp's cosine, twist and quality), so every value is the scalar one bit for
// bit (tested against a scalar reference). Dead slots and lanes past `end` compute on zeros and
// store nothing.
template <class Real>
void MeshStatistics::triangle_terms(const TriMesh<Real>& m, std::size_t begin, std::size_t end, Box& box) {
  double gathered[3][3][kLanes] = {};  // corner, axis, lane
  bool live[kLanes] = {};
  for (std::size_t i = 0; i < end - begin; ++i) {
    const std::size_t t = begin + i;
    if (!m.triangle_alive[t]) continue;
    live[i] = true;
    const Triangle& tri = m.triangle[t];
    for (std::size_t k = 0; k < 3; ++k) {
      const Vec3<double> p = m.position[static_cast<std::size_t>(tri[k])].template cast<double>();
      box.lo = box.lo.cwiseMin(p);
      box.hi = box.hi.cwiseMax(p);
      for (int a = 0; a < 3; ++a) gathered[k][a][i] = p[a];
    }
  }
  L p[3][3];
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) p[k][a] = load_lanes<double>(gathered[k][a]);
  auto cross = [](const L(&u)[3], const L(&v)[3], L(&out)[3]) {
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
  };
  auto sub = [](const L(&u)[3], const L(&v)[3], L(&out)[3]) {
    for (int a = 0; a < 3; ++a) out[a] = u[a] - v[a];
  };

  L e1[3], e2[3], n[3], c[3];
  sub(p[1], p[0], e1);
  sub(p[2], p[0], e2);
  cross(e1, e2, n);
  const L n2 = dot3(n, n);
  const L n_len = lane_sqrt<double>(n2);  // |n|: the area's and the unit normal's
  const L half_area = 0.5 * n_len;
  cross(p[1], p[2], c);
  const L six_volume = dot3(p[0], c);
  const auto has_normal = n2 > 0.0;
  L unit[3];
  for (int a = 0; a < 3; ++a) unit[a] = lane_select<double>(has_normal, n[a] / n_len, L{});

  // Twist (quality.cpp, triangle_twist_deg): the largest cosine between median and mid-line.
  L max_cos = broadcast(-1.0);
  LaneMask<double> degenerate_twist{};
  for (int i = 0; i < 3; ++i) {
    const L(&vi)[3] = p[i];
    const L(&vj)[3] = p[(i + 1) % 3];
    const L(&vk)[3] = p[(i + 2) % 3];
    L median[3], midline[3];
    for (int a = 0; a < 3; ++a) {
      median[a] = 0.5 * (vj[a] + vk[a]) - vi[a];
      midline[a] = 0.5 * (vk[a] - vj[a]);
    }
    const L nu = lane_sqrt<double>(dot3(median, median)), nv = lane_sqrt<double>(dot3(midline, midline));
    degenerate_twist |= (nu == 0.0) | (nv == 0.0);
    const L cos = clamp_unit(dot3(median, midline) / (nu * nv));
    max_cos = lane_max<double>(max_cos, cos);
  }

  // Quality (triangle_quality with the area above).
  L bc[3], ca[3];
  sub(p[2], p[1], bc);
  sub(p[0], p[2], ca);
  const L s2 = (dot3(e1, e1) + dot3(bc, bc)) + dot3(ca, ca);
  constexpr double k4Sqrt3 = 4.0 * std::numbers::sqrt3;  // = 4.0 * std::sqrt(3.0): both correctly rounded
  const L quality = lane_select<double>(s2 == 0.0, L{}, (k4Sqrt3 * half_area) / s2);

  for (std::size_t i = 0; i < end - begin; ++i) {
    if (!live[i]) continue;
    TriangleTerms& T = tri_[begin + i];
    T.half_area = half_area[i];
    T.six_volume = six_volume[i];
    T.twist_deg = degenerate_twist[i] ? 90.0 : 90.0 - std::acos(max_cos[i]) * kDegPerRad;
    T.quality = quality[i];
    unit_normal_[begin + i] = Vec3<double>(unit[0][i], unit[1][i], unit[2][i]);
  }
}

// The length and, for an edge of two uses (ta >= 0), the dihedral measure of `count` <= kLanes
// edges on eight lanes, into edge_ at each edge's first use: the operations of
// (p_lo - p_hi).norm() and quality.cpp's dihedral_deg in their order, so bitwise the scalar values.
template <class Real>
void MeshStatistics::edge_terms(const TriMesh<Real>& m, const PendingEdge* pending, std::size_t count) {
  double gathered[3][3][kLanes] = {};  // the edge vector, n_a, n_b; axis; lane
  for (std::size_t i = 0; i < count; ++i) {
    const PendingEdge& q = pending[i];
    const Vec3<double> d = m.position[static_cast<std::size_t>(q.lo)].template cast<double>() -
                           m.position[static_cast<std::size_t>(q.hi)].template cast<double>();
    for (int a = 0; a < 3; ++a) gathered[0][a][i] = d[a];
    if (q.ta < 0) continue;
    const Vec3<double>& na = unit_normal_[static_cast<std::size_t>(q.ta)];
    const Vec3<double>& nb = unit_normal_[static_cast<std::size_t>(q.tb)];
    for (int a = 0; a < 3; ++a) gathered[1][a][i] = na[a], gathered[2][a][i] = nb[a];
  }
  L v[3][3];
  for (int k = 0; k < 3; ++k)
    for (int a = 0; a < 3; ++a) v[k][a] = load_lanes<double>(gathered[k][a]);
  const L length = lane_sqrt<double>(dot3(v[0], v[0]));
  const L nu = lane_sqrt<double>(dot3(v[1], v[1])), nv = lane_sqrt<double>(dot3(v[2], v[2]));
  const LaneMask<double> no_angle = (nu == 0.0) | (nv == 0.0);
  const L cos = clamp_unit(dot3(v[1], v[2]) / (nu * nv));
  for (std::size_t i = 0; i < count; ++i) {
    EdgeTerms& E = edge_[pending[i].use];
    E.length = length[i];
    if (pending[i].ta >= 0) E.dihedral_deg = no_angle[i] ? 0.0 : std::acos(cos[i]) * kDegPerRad;
  }
}

template <class Real>
const MeshStats& MeshStatistics::compute(const TriMesh<Real>& m) {
  const std::size_t nt = m.triangle_slots(), nv = m.vertex_slots();
  stats_ = MeshStats{};
  QualityReport& r = stats_.quality;
  EulerCounts& c = stats_.topology;

  // 1. The measures of each live triangle, eight slots at a time on SIMD lanes, in parallel:
  //    each slot is written by one task, and the bounding box (min and max are exact in any
  //    order) joined across tasks.
  tri_.resize(nt);
  unit_normal_.resize(nt);
  const Box box = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nt, kGrain), Box{},
      [&](const tbb::blocked_range<std::size_t>& range, Box b) {
        for (std::size_t t = range.begin(); t < range.end(); t += kLanes)
          triangle_terms(m, t, std::min(range.end(), t + kLanes), b);
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
  //    an edge of two uses, the dihedral measure, at the edge's first use, eight edges at a time
  //    on lanes; in parallel.
  edge_.resize(use_.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, kGrain), [&](const tbb::blocked_range<std::size_t>& range) {
    PendingEdge pending[kLanes];
    std::size_t n_pending = 0;
    for (std::size_t lo = range.begin(); lo != range.end(); ++lo) {
      const std::size_t b = start_[lo], e = start_[lo + 1];
      for (std::size_t i = b + 1; i < e; ++i) {
        const EdgeUse x = use_[i];
        std::size_t j = i;
        for (; j > b && use_[j - 1].hi > x.hi; --j) use_[j] = use_[j - 1];
        use_[j] = x;
      }
      for (std::size_t i = b; i < e;) {
        std::size_t j = i + 1;
        while (j < e && use_[j].hi == use_[i].hi) ++j;
        PendingEdge& q = pending[n_pending++];
        q = {i, static_cast<Index>(lo), use_[i].hi, -1, -1};
        if (j - i == 2) {
          q.ta = use_[i].tri >= 0 ? use_[i].tri : ~use_[i].tri;
          q.tb = use_[i + 1].tri >= 0 ? use_[i + 1].tri : ~use_[i + 1].tri;
        }
        if (n_pending == kLanes) edge_terms(m, pending, n_pending), n_pending = 0;
        i = j;
      }
    }
    edge_terms(m, pending, n_pending);
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
template void MeshStatistics::triangle_terms(const TriMesh<float>&, std::size_t, std::size_t, Box&);
template void MeshStatistics::triangle_terms(const TriMesh<double>&, std::size_t, std::size_t, Box&);
template void MeshStatistics::edge_terms(const TriMesh<float>&, const PendingEdge*, std::size_t);
template void MeshStatistics::edge_terms(const TriMesh<double>&, const PendingEdge*, std::size_t);
template const MeshStats& MeshStatistics::compute(const TriMesh<double>&);

}  // namespace meltlab::sim
