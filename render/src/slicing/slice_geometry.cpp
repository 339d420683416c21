// Seed 003's slices (see slicing/slice_geometry.h).

#include <meltlab/render/slicing/slice_geometry.h>

#include "ray_setup.h"

#include <meltlab/core/error.h>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace meltlab::render {

namespace {

std::array<Eigen::Vector3d, 8> corners(const Box3& b) {
  std::array<Eigen::Vector3d, 8> c;
  for (int i = 0; i < 8; ++i)
    c[std::size_t(i)] =
        Eigen::Vector3d(i & 1 ? b.hi.x() : b.lo.x(), i & 2 ? b.hi.y() : b.lo.y(), i & 4 ? b.hi.z() : b.lo.z());
  return c;
}

}  // namespace

std::vector<Eigen::Vector3d> slice_polygon(const Box3& box, const Eigen::Vector3d& n, double d) {
  const auto c = corners(box);
  // The 12 edges p + t v, t ∈ [0, 1] (corner indices differing in one bit).
  std::vector<Eigen::Vector3d> pts;
  const double scale = box.diagonal();
  const double eps_dup = 1e-12 * (scale > 0 ? scale : 1.0);
  for (int i = 0; i < 8; ++i)
    for (int bit = 1; bit < 8; bit <<= 1) {
      if (i & bit) continue;
      const Eigen::Vector3d& p = c[std::size_t(i)];
      const Eigen::Vector3d v = c[std::size_t(i | bit)] - p;
      const double den = n.dot(v);
      if (den == 0) continue;  // edge parallel to the plane (in it: its ends come from other edges)
      const double t = -(n.dot(p) + d) / den;
      if (!(t >= 0 && t <= 1)) continue;
      const Eigen::Vector3d x = p + t * v;
      bool dup = false;
      for (const auto& q : pts) dup = dup || (q - x).cwiseAbs().maxCoeff() <= eps_dup;
      if (!dup) pts.push_back(x);
    }
  if (pts.size() < 3) return {};
  // Order about the centroid by the angle in a plane basis (e1, e2 = n̂ × e1): counter-clockwise about n.
  const Eigen::Vector3d nn = n.normalized();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : pts) centroid += p;
  centroid /= double(pts.size());
  const Eigen::Vector3d e1 =
      (std::abs(nn.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(nn).normalized();
  const Eigen::Vector3d e2 = nn.cross(e1);
  std::vector<std::pair<double, Eigen::Vector3d>> a;
  for (const auto& p : pts) a.emplace_back(std::atan2((p - centroid).dot(e2), (p - centroid).dot(e1)), p);
  std::sort(a.begin(), a.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<Eigen::Vector3d> out;
  for (const auto& [ang, p] : a) out.push_back(p);
  // A plane through an edge or a corner only: collinear points (zero area) are no polygon.
  if (!(polygon_area(out, nn) > 1e-14 * scale * scale)) return {};
  return out;
}

double polygon_area(const std::vector<Eigen::Vector3d>& poly, const Eigen::Vector3d& n) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < poly.size(); ++i) s += poly[i].cross(poly[(i + 1) % poly.size()]);
  return 0.5 * s.dot(n.normalized());
}

double slice_spacing(double quality_class, const Eigen::Vector3d& voxel_spacing) {
  return quality_class * voxel_spacing.minCoeff();
}

SliceStack slice_stack(const Box3& box, const Eigen::Vector3d& eye, double spacing, SliceRange range) {
  const Eigen::Vector3d to_centre = box.centre() - eye;
  if (!(to_centre.norm() > 0)) throw InputError("slicing: the eye is at the volume's centre (no view direction)");
  if (!(spacing > 0 && std::isfinite(spacing)))
    throw InputError(fmt::format("slicing: the slice spacing must be > 0 (got {})", spacing));
  SliceStack st;
  st.n = to_centre.normalized();
  st.spacing = spacing;
  double s_min = 0, s_max = 0;
  if (range == SliceRange::kTight) {
    s_min = 1e300, s_max = -1e300;
    for (const auto& c : corners(box)) {
      s_min = std::min(s_min, st.n.dot(c));
      s_max = std::max(s_max, st.n.dot(c));
    }
  } else {
    // The source's bound about the box's lower corner (its origin): |d| <= D.
    const Eigen::Vector3d L = box.size();
    const double D = st.n.cwiseAbs().dot(L);
    const double s0 = st.n.dot(box.lo);
    s_min = s0 - D, s_max = s0 + D;
  }
  st.s_max = s_max;
  const double count = std::ceil((s_max - s_min) / spacing);
  if (!(count <= 1e6))
    throw InputError(fmt::format("slicing: {} slices (spacing {}) exceed the limit of 1e6", count, spacing));
  st.count = std::max(0, int(count));
  return st;
}

RaySlices ray_slices(const SliceStack& st, const Box3& box, const Eigen::Vector3d& o, const Eigen::Vector3d& v) {
  // The slicing renderer's set-up for one ray (ray_setup.h: its packets compute the same bits).
  const ray_setup::Frame f = ray_setup::plane_frame(st, box, o);
  const double dir[3] = {v.x(), v.y(), v.z()};
  const ray_setup::Planes<double> p = ray_setup::planes_of(f, dir);
  RaySlices r;
  r.cos_psi = p.cos_psi, r.t_offset = f.t_offset;
  if (p.miss) return r;
  r.k_first = p.k_first, r.k_last = p.k_last;
  return r;
}

}  // namespace meltlab::render
