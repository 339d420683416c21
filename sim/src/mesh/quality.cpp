#include <meltlab/sim/quality.h>

#include "vertex_sort.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

namespace meltlab::sim {

namespace {
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// cos of the angle between u and v, clamped to [-1, 1]; none if either is the zero vector.
std::optional<double> cosine(const Vec3<double>& u, const Vec3<double>& v) {
  const double nu = u.norm(), nv = v.norm();
  if (nu == 0.0 || nv == 0.0) return std::nullopt;
  return std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0);
}

double angle_deg(const Vec3<double>& u, const Vec3<double>& v) {
  const std::optional<double> c = cosine(u, v);
  return c ? std::acos(*c) * kDegPerRad : 0.0;
}
}  // namespace

// Twist (Eq. 2.4). For corner i the median runs from v_i to the midpoint of the opposite
// side; the mid-line joins the midpoints of the two sides at v_i and is parallel to the
// opposite side. alpha_i is the angle between them, min over the corners; s = 90° - alpha.
// Dot(median_i, midline_i) = (|v_k - v_i|² - |v_j - v_i|²)/4, and these sum to zero over the
// three corners, so min alpha <= 90° and s >= 0 (s = 0 exactly for equilateral triangles).
// The smallest angle has the largest cosine: one arccosine per triangle instead of three.
double triangle_twist_deg(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c) {
  const Vec3<double>* v[3] = {&a, &b, &c};
  double max_cos = -1.0;
  for (int i = 0; i < 3; ++i) {
    const Vec3<double>& vi = *v[i];
    const Vec3<double>& vj = *v[(i + 1) % 3];
    const Vec3<double>& vk = *v[(i + 2) % 3];
    const Vec3<double> median = 0.5 * (vj + vk) - vi;
    const Vec3<double> midline = 0.5 * (vk - vj);
    const std::optional<double> cos_alpha = cosine(median, midline);
    if (!cos_alpha) return 90.0;  // degenerate
    max_cos = std::max(max_cos, *cos_alpha);
  }
  return 90.0 - std::acos(max_cos) * kDegPerRad;
}

double triangle_quality(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c) {
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const double s2 = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  if (s2 == 0.0) return 0.0;
  return 4.0 * std::sqrt(3.0) * area / s2;
}

template <class Real>
double mesh_volume(const TriMesh<Real>& m) {
  double six_v = 0.0;
  for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    const Vec3<double> a = m.position[static_cast<std::size_t>(tri[0])].template cast<double>();
    const Vec3<double> b = m.position[static_cast<std::size_t>(tri[1])].template cast<double>();
    const Vec3<double> c = m.position[static_cast<std::size_t>(tri[2])].template cast<double>();
    six_v += a.dot(b.cross(c));
  }
  return six_v / 6.0;
}

template <class Real>
QualityReport mesh_quality(const TriMesh<Real>& m) {
  QualityReport r;
  r.bbox_min.setConstant(std::numeric_limits<double>::infinity());
  r.bbox_max.setConstant(-std::numeric_limits<double>::infinity());
  struct HalfEdge {
    std::uint64_t key;
    Index tri;
  };
  std::vector<HalfEdge> half;
  half.reserve(3 * m.triangle_slots());
  std::vector<Vec3<double>> unit_normal(m.triangle_slots(), Vec3<double>::Zero());
  double sum_s = 0, sum_q = 0, six_v = 0;
  std::int64_t nf = 0;
  r.min_q = 1.0;
  for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    Vec3<double> p[3];
    for (int k = 0; k < 3; ++k) {
      p[k] = m.position[static_cast<std::size_t>(tri[static_cast<std::size_t>(k)])].template cast<double>();
      r.bbox_min = r.bbox_min.cwiseMin(p[k]);
      r.bbox_max = r.bbox_max.cwiseMax(p[k]);
    }
    const Vec3<double> n = (p[1] - p[0]).cross(p[2] - p[0]);
    r.area += 0.5 * n.norm();
    six_v += p[0].dot(p[1].cross(p[2]));
    if (n.squaredNorm() > 0) unit_normal[t] = n.normalized();
    sum_s += triangle_twist_deg(p[0], p[1], p[2]);
    const double q = triangle_quality(p[0], p[1], p[2]);
    sum_q += q;
    r.min_q = std::min(r.min_q, q);
    ++nf;
    for (int k = 0; k < 3; ++k) {
      const auto u = static_cast<std::uint64_t>(tri[static_cast<std::size_t>(k)]);
      const auto w = static_cast<std::uint64_t>(tri[static_cast<std::size_t>((k + 1) % 3)]);
      half.push_back({(std::min(u, w) << 32) | std::max(u, w), static_cast<Index>(t)});
    }
  }
  r.volume = six_v / 6.0;
  if (nf == 0) {
    r.bbox_min.setZero();
    r.bbox_max.setZero();
    r.min_q = 0;
    return r;
  }
  r.Qs = sum_s / static_cast<double>(nf);
  r.Qq = sum_q / static_cast<double>(nf);
  // Ascending (key, tri): the half-edges were added in ascending triangle order.
  sort_by_vertex_pair(half, m.vertex_slots());
  double sum_d = 0, sum_len = 0;
  std::int64_t n_len = 0;
  for (std::size_t i = 0; i < half.size();) {
    std::size_t j = i;
    while (j < half.size() && half[j].key == half[i].key) ++j;
    const auto lo = static_cast<std::size_t>(half[i].key >> 32);
    const auto hi = static_cast<std::size_t>(half[i].key & 0xffffffffu);
    sum_len += (m.position[lo].template cast<double>() - m.position[hi].template cast<double>()).norm();
    ++n_len;
    if (j - i == 2) {
      const double d = angle_deg(unit_normal[static_cast<std::size_t>(half[i].tri)],
                                 unit_normal[static_cast<std::size_t>(half[i + 1].tri)]);
      sum_d += d;
      r.max_d = std::max(r.max_d, d);
      ++r.edges;
    }
    i = j;
  }
  r.Qd = r.edges > 0 ? sum_d / static_cast<double>(r.edges) : 0.0;
  r.mean_edge_length = n_len > 0 ? sum_len / static_cast<double>(n_len) : 0.0;
  return r;
}

template QualityReport mesh_quality(const TriMesh<float>&);
template QualityReport mesh_quality(const TriMesh<double>&);
template double mesh_volume(const TriMesh<float>&);
template double mesh_volume(const TriMesh<double>&);

}  // namespace meltlab::sim
