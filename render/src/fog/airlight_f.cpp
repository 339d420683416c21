// F(u, v) of seed 002 (fog/airlight_f.h).

#include <meltlab/render/fog/airlight_f.h>

#include <meltlab/core/error.h>
#include <meltlab/render/fog/quadrature.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace meltlab::render::fog {

namespace {

constexpr double kHalfPi = std::numbers::pi / 2;
// Relative tolerance of each Gauss–Kronrod piece: the K15 value of a converged piece is far more
// accurate than the |K15 - G7| estimate this bounds (measured: 1e-13 or better against the
// ζ-form by tanh-sinh, tests/render/fog/airlight_f_test.cpp).
constexpr double kTolerance = 1e-12;
// exp(-745) underflows to 0 in double: the integrand vanishes beyond u·w = kUnderflow.
constexpr double kUnderflow = 745.0;
// v within this of an end of [0, π/2] is taken as that end (rounding of callers' π/4 + ½ atan).
constexpr double kEndSlack = 1e-12;

double check_v(double v, const char* what) {
  if (!(v >= -kEndSlack && v <= kHalfPi + kEndSlack))
    throw InvariantError(fmt::format("airlight_f: {} = {} is outside [0, π/2]", what, v));
  return std::clamp(v, 0.0, kHalfPi);
}

// ∫_{w0}^{w1} exp(-u (w - shift))/(1 + w²) dw, 0 <= shift <= w0 <= w1 <= ∞.
double integrate_w(double u, double w0, double w1, double shift = 0.0) {
  if (u > 0) w1 = std::min(w1, shift + kUnderflow / u);
  if (!(w1 > w0)) return 0.0;
  // Knots: 1 (the Lorentzian's scale) and shift + 1/u (the cut-off's), inside (w0, w1).
  std::array<double, 4> knots{w0, w1, w1, w1};
  int n = 1;
  for (double k : {1.0, u > 0 ? shift + 1.0 / u : w1})
    if (k > w0 && k < w1) knots[static_cast<std::size_t>(n++)] = k;
  knots[static_cast<std::size_t>(n)] = w1;
  for (int i = 1; i <= n; ++i)  // insertion sort of at most 4 knots
    for (int j = i; j > 0 && knots[static_cast<std::size_t>(j) - 1] > knots[static_cast<std::size_t>(j)]; --j)
      std::swap(knots[static_cast<std::size_t>(j) - 1], knots[static_cast<std::size_t>(j)]);
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double lo = knots[static_cast<std::size_t>(i)], hi = knots[static_cast<std::size_t>(i) + 1];
    if (!(hi > lo)) continue;
    if (lo >= 1.0 && std::isfinite(hi)) {
      // r = ln w: dw = w dr; the integrand exp(-u e^r) e^r / (1 + e^{2r}) is smooth at both scales.
      auto f = [u, shift](double r) {
        const double w = std::exp(r);
        return std::exp(-u * (w - shift)) * w / (1.0 + w * w);
      };
      sum += integrate_gk(f, std::log(lo), std::log(hi), kTolerance);
    } else if (lo >= 1.0) {
      // u = 0 and an infinite end: ∫_lo^∞ dw/(1 + w²) = π/2 - atan(lo) = atan(1/lo).
      sum += std::atan(1.0 / lo);
    } else {
      auto f = [u, shift](double w) { return std::exp(-u * (w - shift)) / (1.0 + w * w); };
      sum += integrate_gk(f, lo, hi, kTolerance);
    }
  }
  return sum;
}

double tan_of(double v) { return v >= kHalfPi ? std::numeric_limits<double>::infinity() : std::tan(v); }

}  // namespace

double airlight_f(double u, double v) {
  if (!(u >= 0) || !std::isfinite(u)) throw InvariantError(fmt::format("airlight_f: u = {} is not >= 0", u));
  v = check_v(v, "v");
  if (u == 0) return v;
  return integrate_w(u, 0.0, tan_of(v));
}

double airlight_f_between(double u, double v0, double v1) {
  if (!(u >= 0) || !std::isfinite(u)) throw InvariantError(fmt::format("airlight_f_between: u = {} is not >= 0", u));
  v0 = check_v(v0, "v0");
  v1 = check_v(v1, "v1");
  if (!(v1 > v0)) return 0.0;
  if (u == 0) return v1 - v0;
  return integrate_w(u, tan_of(v0), tan_of(v1));
}

double airlight_h(double u, double v) {
  if (!(u >= 0) || !std::isfinite(u)) throw InvariantError(fmt::format("airlight_h: u = {} is not >= 0", u));
  v = check_v(v, "v");
  if (v >= kHalfPi) return 0.0;
  if (u == 0) return kHalfPi - v;
  const double T = std::tan(v);
  return integrate_w(u, T, std::numeric_limits<double>::infinity(), T);
}

double airlight_f_dv(double u, double v) {
  v = check_v(v, "v");
  if (u == 0) return 1.0;
  return v >= kHalfPi ? 0.0 : std::exp(-u * std::tan(v));
}

}  // namespace meltlab::render::fog
