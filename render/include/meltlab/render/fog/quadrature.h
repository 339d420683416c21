#pragma once
// Boost.Math's adaptive Gauss–Kronrod 15/7 for the fog family, with a workaround: Boost 1.74's
// recursive_adaptive_integrate compares the error estimate of a sub-interval on [-1, 1]
// (unscaled, and floored at 2ε|K|) with a tolerance scaled by the sub-interval's half-width, so
// any sub-interval narrower than about 2ε/tol of the original recurses to the maximum depth
// (2^depth evaluations: an interval of width 1e-6 at tol 1e-10 never returns). Mapping [a, b]
// onto [-1, 1] here makes the half-width 1 at the top, and a depth below log2(tol/2ε) keeps the
// floor out of reach: the integral is then Boost's, to the requested relative tolerance.

#include <boost/math/quadrature/gauss_kronrod.hpp>

#include <algorithm>
#include <cmath>

namespace meltlab::render::fog {

/// ∫_a^b f by adaptive Gauss–Kronrod 15/7, relative tolerance `rel_tol` (>= 1e-13), a and b
/// finite. The recursion depth is the largest for which the Boost 1.74 floor stays unreachable.
template <class F>
double integrate_gk(F f, double a, double b, double rel_tol = 1e-11) {
  if (!(b > a)) return 0.0;
  const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
  // 2^-depth > 2ε/tol: the sub-interval tolerance stays above the estimate's floor.
  const double floor_ratio = 2 * 2.220446049250313e-16 / rel_tol;
  const unsigned depth = static_cast<unsigned>(std::clamp(std::floor(-std::log2(floor_ratio)) - 1, 1.0, 30.0));
  using GK = boost::math::quadrature::gauss_kronrod<double, 15>;
  return half * GK::integrate([&](double x) { return f(mid + half * x); }, -1.0, 1.0, depth, rel_tol);
}

}  // namespace meltlab::render::fog
