#pragma once
// Ray differentials (pbrt's scheme): the footprint of a pixel, for MIP-mapped texture lookups
// (texture/lookup.h). A point or direction of this pixel's ray changes by `dx` towards the ray
// through the next pixel to the right and by `dy` towards the one below. The integrator carries
// them from the camera rays to the surfaces it hits (plane_footprint) and the materials through
// reflection and refraction (material/optics.h's reflect_differential, refract_differential).

#include <Eigen/Core>

namespace meltlab::render {

/// The change of a point or of a direction per pixel step in x and in y.
struct Differential {
  Eigen::Vector3d dx = Eigen::Vector3d::Zero(), dy = Eigen::Vector3d::Zero();
};
/// The footprint of a ray: of its origin and of its (unit) direction.
struct RayDifferential {
  Differential o, d;
};
/// The change of 2D texture coordinates (s, t) per pixel step: d(s,t)/dx, d(s,t)/dy.
struct Differential2 {
  Eigen::Vector2d dx = Eigen::Vector2d::Zero(), dy = Eigen::Vector2d::Zero();
};

/// Where the two neighbouring rays of `rd` (this ray: o + t·d) meet the plane through p with
/// normal n, relative to p. A neighbour that misses the plane (at the horizon) meets it at
/// distance `far`: a huge footprint.
Differential plane_footprint(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const RayDifferential& rd,
                             const Eigen::Vector3d& p, const Eigen::Vector3d& n, double far);

/// The footprint of reflect(V, N) (material/optics.h) from that of the ray direction `dd`
/// (= -dV) and that of the normal `dN`.
Differential reflected_footprint(const Eigen::Vector3d& V, const Differential& dd, const Eigen::Vector3d& N,
                                 const Differential& dN);

}  // namespace meltlab::render
