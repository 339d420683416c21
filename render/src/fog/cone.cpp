// The lit part of a view ray (fog/cone.h).

#include <meltlab/render/fog/cone.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meltlab::render::fog {

namespace {

// |c2| below this (relative to the scale of the other coefficients) is the linear case: the
// ray is parallel to a generator of the cone and the quadratic has one finite root.
constexpr double kLinearEps = 1e-14;

// The quadratic's coefficients (spec §2.5) for the ray s·V̂.
struct Quadratic {
  double c2, c1, c0;
};
Quadratic cone_quadratic(const Vec3& V, const Cone& cone) {
  const Vec3& S = cone.apex;
  const Vec3& D = cone.axis;
  const double cc = cone.cos_half * cone.cos_half;
  const double vd = V.dot(D), sd = S.dot(D);
  // M = D̂D̂ᵀ - cos² I:  VᵀMV = (V·D)² - cos²,  VᵀMS = (V·D)(S·D) - cos² V·S,  SᵀMS = (S·D)² - cos² |S|².
  return {vd * vd - cc, -(vd * sd - cc * V.dot(S)), sd * sd - cc * S.squaredNorm()};
}

// Real roots of c2 s² + 2 c1 s + c0 = 0 (stable form); returns their number (0..2).
int real_roots(const Quadratic& q, double& r0, double& r1) {
  const double scale = std::max({std::abs(q.c0), std::abs(q.c1), 1e-300});
  if (std::abs(q.c2) <= kLinearEps * scale) {
    if (q.c1 == 0) return 0;
    r0 = -q.c0 / (2 * q.c1);
    return 1;
  }
  const double disc = q.c1 * q.c1 - q.c0 * q.c2;
  if (disc < 0) return 0;
  const double root = std::sqrt(disc);
  const double k = -(q.c1 + std::copysign(root, q.c1));  // no cancellation
  if (k == 0) {                                          // c1 = c0 = 0: a double root at 0
    r0 = r1 = 0;
    return 2;
  }
  r0 = k / q.c2;
  r1 = q.c0 / k;
  if (r0 > r1) std::swap(r0, r1);
  return 2;
}

// A root of the quadratic refined by Newton steps on its own nappe's surface function
// g(s) = D̂·d ∓ cos θ_c |d| (d = sV̂ - S): near the apex the quadratic's roots are conditioned as
// sqrt(ε) (a double root at the apex itself), g's simple root as ε.
double polish_root(const Vec3& V, const Cone& cone, double s) {
  const double c = cone.cos_half;
  for (int it = 0; it < 3; ++it) {
    const Vec3 d = s * V - cone.apex;
    const double dn = d.norm();
    if (!(dn > 0)) break;
    const double sign = cone.axis.dot(d) >= 0 ? -1.0 : 1.0;  // forward nappe: D·d - c|d|
    const double g = cone.axis.dot(d) + sign * c * dn;
    const double dg = cone.axis.dot(V) + sign * c * d.dot(V) / dn;
    if (!(std::abs(dg) > 1e-12)) break;
    const double step = g / dg;
    if (!(std::abs(step) <= 1e-6 * std::max(1.0, std::abs(s)))) break;  // only a polish
    s -= step;
  }
  return s;
}

}  // namespace

bool inside_cone(const Cone& cone, const Vec3& x) {
  const Vec3 d = x - cone.apex;
  return cone.axis.dot(d) >= cone.cos_half * d.norm();
}

ConeSegments segment_in_cone(const Vec3& V, double m, const Cone& cone) {
  ConeSegments out;
  if (!(m > 0)) return out;
  double r[2];
  const int n = real_roots(cone_quadratic(V, cone), r[0], r[1]);
  std::array<double, 4> knots{};
  int k = 0;
  knots[static_cast<std::size_t>(k++)] = 0.0;
  for (int i = 0; i < n; ++i) {
    const double root = std::isfinite(r[i]) ? polish_root(V, cone, r[i]) : r[i];
    if (root > 0 && root < m) knots[static_cast<std::size_t>(k++)] = root;
  }
  knots[static_cast<std::size_t>(k++)] = m;
  for (int i = 1; i < k; ++i)  // insertion sort of at most 4 knots
    for (int j = i; j > 0 && knots[static_cast<std::size_t>(j) - 1] > knots[static_cast<std::size_t>(j)]; --j)
      std::swap(knots[static_cast<std::size_t>(j) - 1], knots[static_cast<std::size_t>(j)]);
  for (int i = 0; i + 1 < k; ++i) {
    const double lo = knots[static_cast<std::size_t>(i)], hi = knots[static_cast<std::size_t>(i) + 1];
    if (!(hi > lo)) continue;
    // The midpoint of an unbounded last interval: any point beyond the last root will do.
    const double mid = std::isfinite(hi) ? 0.5 * (lo + hi) : 2 * lo + 1;
    if (!inside_cone(cone, mid * V)) continue;
    if (out.count > 0 && out.parts[static_cast<std::size_t>(out.count) - 1].b == lo)
      out.parts[static_cast<std::size_t>(out.count) - 1].b = hi;  // a root where the ray only touches
    else if (out.count < 2)
      out.parts[static_cast<std::size_t>(out.count++)] = {lo, hi};
  }
  return out;
}

Interval segment_in_cone_source(const Vec3& V, double m, const Cone& cone) {
  const Quadratic q = cone_quadratic(V, cone);
  const double disc = q.c1 * q.c1 - q.c0 * q.c2;
  if (!(disc >= 0)) return {};  // main(): nothing computed
  // IntersectionPoints() as printed.
  double s1 = (-q.c1 + std::sqrt(disc)) / q.c2;
  double s2 = (-q.c1 - std::sqrt(disc)) / q.c2;
  const double ss = std::min(s1, s2);
  s2 = std::max(s1, s2);
  s1 = ss;
  const Vec3 x1 = s1 * V, x2 = s2 * V;
  double a = s1, b = s2;
  const double d1 = cone.axis.dot((x1 - cone.apex).normalized());
  const double d2 = cone.axis.dot((x2 - cone.apex).normalized());
  if (d1 <= 0.) {
    a = s2;
    b = m;
  }
  if (d2 <= 0.) {
    a = 0.;
    b = s1;
    if (d1 < 0.) b = 0.;  // no intersection
  }
  // main(): clamp(ab, 0, Dvp).
  a = std::clamp(a, 0.0, m);
  b = std::clamp(b, 0.0, m);
  if (std::isnan(a) || std::isnan(b)) return {};
  return {a, b};
}

}  // namespace meltlab::render::fog
