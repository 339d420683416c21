// Ray differentials (ray_differential.h).

#include <meltlab/render/ray_differential.h>
#include <meltlab/render/material/optics.h>

#include <cmath>

namespace meltlab::render {

using Eigen::Vector3d;

Differential plane_footprint(const Vector3d& o, const Vector3d& d, const RayDifferential& rd, const Vector3d& p,
                             const Vector3d& n, double far) {
  auto at = [&](const Vector3d& dox, const Vector3d& ddx) -> Vector3d {
    const Vector3d o2 = o + dox, d2 = d + ddx;
    const double den = n.dot(d2);
    double t = std::abs(den) > 1e-12 ? n.dot(p - o2) / den : far;
    if (!(t > 0) || t > far) t = far;  // the neighbour misses the plane (the horizon): a huge footprint
    return o2 + t * d2 - p;
  };
  return {at(rd.o.dx, rd.d.dx), at(rd.o.dy, rd.d.dy)};
}

Differential reflected_footprint(const Vector3d& V, const Differential& dd, const Vector3d& N, const Differential& dN) {
  return {reflect_differential(V, -dd.dx, N, dN.dx), reflect_differential(V, -dd.dy, N, dN.dy)};
}

}  // namespace meltlab::render
