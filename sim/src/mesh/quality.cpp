#include <meltlab/sim/mesh_stats.h>
#include <meltlab/sim/quality.h>

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

}  // namespace

double dihedral_deg(const Vec3<double>& n_a, const Vec3<double>& n_b) {
  const std::optional<double> c = cosine(n_a, n_b);
  return c ? std::acos(*c) * kDegPerRad : 0.0;
}

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
  return triangle_quality(0.5 * (b - a).cross(c - a).norm(), a, b, c);
}

double triangle_quality(double area, const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c) {
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
  MeshStatistics stats;
  return stats.compute(m).quality;
}

template QualityReport mesh_quality(const TriMesh<float>&);
template QualityReport mesh_quality(const TriMesh<double>&);
template double mesh_volume(const TriMesh<float>&);
template double mesh_volume(const TriMesh<double>&);

}  // namespace meltlab::sim
