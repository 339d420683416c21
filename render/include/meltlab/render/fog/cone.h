#pragma once
// The part of a view ray inside a spotlight's cone (spec fog-spotlight-airlight.md §2.5).
//
// Frame: any frame with the ray's origin (the eye, or a surface point for the surface
// references) at 0; `apex` is the light's position S relative to that origin, `axis` the unit
// spot direction D̂, `cos_half` = cos θ_c. A point X is lit when D̂·(X - S) >= cos θ_c |X - S|
// (the forward nappe only: the light shines along +D̂). The ray is X = s·V̂, s in [0, m]
// (metres; m may be +∞).
//
// segment_in_cone (fsa.cone.solver = robust, the harness's): the roots of the double cone's
// quadratic c2 s² + 2 c1 s + c0 = 0 (c2 = V̂ᵀMV̂, c1 = -V̂ᵀMS, c0 = SᵀMS, M = D̂D̂ᵀ - cos²θ_c I;
// the linear case when c2 ≈ 0) inside (0, m) are knots with 0 and m; each knot interval whose
// midpoint is lit belongs to the segment. No special cases: the eye inside the cone, the light
// behind the eye, grazing rays and rays through the apex all follow. For θ_c < 90° the lit set
// of a line is convex (one interval); for θ_c >= 90° (a cone wider than a half-space, and the
// point-light limit θ_c -> π) it may be two.
//
// segment_in_cone_source: the listing's IntersectionPoints() and main() of the thesis (Fig.
// 4.1, 4.3) as printed: nothing when the discriminant is negative (also when the whole ray is
// inside the cone), the wrong nappe handled by its three special cases, then clamped to
// [0, m]. Kept to count the pixels where it differs (spec §6 target 5).

#include <Eigen/Geometry>

#include <array>

namespace meltlab::render::fog {

using Vec3 = Eigen::Vector3d;

/// A distance interval [a, b] along the ray (metres from its origin).
struct Interval {
  double a = 0, b = 0;
  double length() const { return b - a; }
};

/// The lit part of a ray: up to two disjoint intervals in increasing order (one for θ_c < 90°).
struct ConeSegments {
  std::array<Interval, 2> parts{};
  int count = 0;
  bool empty() const { return count == 0; }
  /// The hull [first a, last b] (the single interval for θ_c < 90°); {0, 0} if empty.
  Interval hull() const { return count == 0 ? Interval{} : Interval{parts[0].a, parts[count - 1].b}; }
};

/// A spot cone: apex relative to the ray origin, unit axis, cos of the half-angle (in (-1, 1]).
struct Cone {
  Vec3 apex = Vec3::Zero();
  Vec3 axis = Vec3(0, 0, -1);
  double cos_half = 0.8660254037844387;  ///< cos 30°
};

/// Whether point x (same frame) is lit by the cone: D̂·(x - S) >= cos θ_c |x - S|.
bool inside_cone(const Cone& cone, const Vec3& x);

/// The lit part of the ray s·V̂, s in [0, m] (V̂ unit; m > 0, may be +∞). Robust method above.
ConeSegments segment_in_cone(const Vec3& view_dir, double m, const Cone& cone);

/// The listing's method (see above): one interval [a, b] (a = b when it finds nothing).
Interval segment_in_cone_source(const Vec3& view_dir, double m, const Cone& cone);

}  // namespace meltlab::render::fog
