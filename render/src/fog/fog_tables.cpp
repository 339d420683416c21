// The F and G_n tables of seed 002 (fog/fog_tables.h).

#include <meltlab/render/fog/fog_tables.h>

#include <meltlab/core/error.h>
#include <meltlab/render/fog/airlight_f.h>

#include <boost/math/quadrature/gauss.hpp>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace meltlab::render::fog {

namespace {

TableAxis make_axis(const char* name, double lo, double hi, int n, AxisWarp warp) {
  TableAxis a;
  a.name.assign(name);
  a.lo = lo;
  a.hi = hi;
  a.n = n;
  a.warp = warp;
  return a;
}

constexpr double kPi = std::numbers::pi;
// Panels of the φ quadrature: at most this wide (rad), graded geometrically towards φ = 0 over
// kGradingLevels halvings (D_T(φ) ~ φ ln φ there). 8-point Gauss–Legendre per panel: with
// panels of π/128 the rule's error on the smooth pieces is far below 1e-10 (checked against an
// adaptive 2-D integral in the tests).
constexpr double kMaxPanel = kPi / 128;
constexpr int kGradingLevels = 24;
// Phong exponents up to this (the binomial sum of ring_weight has n + 1 terms).
constexpr int kMaxExponent = 500;

// The φ nodes and weights of the composite rule with the given extra panel edges.
struct PhiRule {
  std::vector<double> phi, weight;
};
PhiRule phi_rule(std::vector<double> edges) {
  edges.push_back(0.0);
  edges.push_back(kPi);
  for (int k = 0; k <= kGradingLevels; ++k) edges.push_back(kMaxPanel * std::ldexp(1.0, -k));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end(), [](double a, double b) { return b - a < 1e-15; }), edges.end());
  using GL = boost::math::quadrature::gauss<double, 8>;
  PhiRule r;
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
    const double lo = edges[i], hi = edges[i + 1];
    const int pieces = std::max(1, static_cast<int>(std::ceil((hi - lo) / kMaxPanel - 1e-9)));
    for (int p = 0; p < pieces; ++p) {
      const double a = lo + (hi - lo) * p / pieces, b = lo + (hi - lo) * (p + 1) / pieces;
      const double c = 0.5 * (a + b), h = 0.5 * (b - a);
      for (std::size_t k = 0; k < GL::abscissa().size(); ++k) {
        const double x = GL::abscissa()[k], w = GL::weights()[k];
        r.phi.push_back(c + h * x);
        r.weight.push_back(h * w);
        if (x != 0) {
          r.phi.push_back(c - h * x);
          r.weight.push_back(h * w);
        }
      }
    }
  }
  return r;
}

// The kinks of W_n(·, θ) in φ.
void add_kinks(double theta, std::vector<double>& edges) {
  const double k = std::abs(0.5 * kPi - theta);
  edges.push_back(k);
  edges.push_back(kPi - k);
}

// e^{-T cos φ} D_T(φ).
double g_kernel(double T, double phi) {
  return std::exp(-T * std::cos(phi)) * airlight_f_between(T * std::sin(phi), 0.5 * phi, 0.5 * kPi);
}

}  // namespace

const char* axis_warp_name(AxisWarp w) {
  switch (w) {
    case AxisWarp::kSqrt:
      return "sqrt";
    case AxisWarp::kCbrt:
      return "cbrt";
    case AxisWarp::kSqrtHi:
      return "sqrt_hi";
    case AxisWarp::kSmooth:
      return "smooth";
    case AxisWarp::kNone:
      break;
  }
  return "none";
}

AxisWarp parse_axis_warp(const std::string& name, const std::string& where) {
  for (AxisWarp w : {AxisWarp::kNone, AxisWarp::kSqrt, AxisWarp::kCbrt, AxisWarp::kSqrtHi, AxisWarp::kSmooth})
    if (name == axis_warp_name(w)) return w;
  throw InputError(fmt::format("{}: unknown axis warp '{}' (none, sqrt, cbrt, sqrt_hi, smooth)", where, name));
}

const char* interp_space_name(InterpSpace s) { return s == InterpSpace::kValue ? "value" : "index"; }

InterpSpace parse_interp_space(const std::string& name, const std::string& where) {
  if (name == "index") return InterpSpace::kIndex;
  if (name == "value") return InterpSpace::kValue;
  throw InputError(fmt::format("{}: unknown interpolation space '{}' (index, value)", where, name));
}

double TableAxis::node(int i) const {
  const double s = n > 1 ? static_cast<double>(i) / (n - 1) : 0.0;
  switch (warp) {
    case AxisWarp::kSqrt:
      return lo + (hi - lo) * s * s;
    case AxisWarp::kCbrt:
      return lo + (hi - lo) * s * s * s;
    case AxisWarp::kSqrtHi:
      return i + 1 == n ? hi : hi - (hi - lo) * (1 - s) * (1 - s);
    case AxisWarp::kSmooth:
      return i + 1 == n ? hi : lo + (hi - lo) * s * s * (3 - 2 * s);
    case AxisWarp::kNone:
      break;
  }
  return lo + (hi - lo) * s;
}

double TableAxis::index(double x, bool& clamped) const {
  const double slack = 1e-12 * std::max(1.0, std::abs(hi - lo));
  if (x < lo - slack || x > hi + slack) clamped = true;
  double s = std::clamp((x - lo) / (hi - lo), 0.0, 1.0);
  switch (warp) {
    case AxisWarp::kSqrt:
      s = std::sqrt(s);
      break;
    case AxisWarp::kCbrt:
      s = std::cbrt(s);
      break;
    case AxisWarp::kSqrtHi:
      s = 1 - std::sqrt(1 - s);
      break;
    // The inverse of 3s² - 2s³ on [0, 1] (the cubic's trigonometric root).
    case AxisWarp::kSmooth:
      s = 0.5 - std::sin(std::asin(1 - 2 * s) / 3);
      break;
    case AxisWarp::kNone:
      break;
  }
  const double index = s * (n - 1);
  if (space == InterpSpace::kIndex || warp == AxisWarp::kNone || n < 2) return index;
  const int i = std::clamp(static_cast<int>(index), 0, n - 2);
  const double x0 = node(i), x1 = node(i + 1);
  return i + std::clamp((std::clamp(x, lo, hi) - x0) / (x1 - x0), 0.0, 1.0);
}

double FogTable::lookup(double xv, double yv, bool* clamped) const {
  bool c = false;
  const double ix = x.index(xv, c), iy = y.index(yv, c);
  if (clamped && c) *clamped = true;
  return sample_bilinear_inside(values, ix, iy);  // index() keeps both inside the nodes
}

std::string FogTable::describe() const {
  return fmt::format(
      "{}: x = {} in [{}, {}] ({} nodes, warp {}, linear in {} space), y = {} in [{}, {}] ({} nodes, warp {}, "
      "linear in {} space), bilinear, float, clamped beyond",
      name, x.name, x.lo, x.hi, x.n, axis_warp_name(x.warp), interp_space_name(x.space), y.name, y.lo, y.hi, y.n,
      axis_warp_name(y.warp), interp_space_name(y.space));
}

namespace {

// The empty F or H table over (v, u) (the two share their axes, fsa.table.F.u_max included).
FogTable empty_vu_table(const char* name, const TableOptions& o) {
  if (o.n < 2) throw InputError(fmt::format("fsa.table.N = {}: at least 2 nodes per axis", o.n));
  if (!(o.u_max > 0)) throw InputError(fmt::format("fsa.table.F.u_max = {}: must be > 0", o.u_max));
  FogTable t;
  t.name = fmt::format("{}", name);  // (not = name: a false -Wrestrict of GCC 12)
  t.x = make_axis("v", 0.0, 0.5 * kPi, o.n, o.v_warp);
  t.y = make_axis("u", 0.0, o.u_max, o.n, o.u_warp);
  t.x.space = o.v_interp;
  t.values = ImageF(o.n, o.n, 1);
  return t;
}

}  // namespace

FogTable f_table(const TableOptions& o) {
  FogTable t = empty_vu_table("F", o);
  tbb::parallel_for(0, o.n, [&](int j) {
    const double u = t.y.node(j);
    // Along a row, F accumulates interval by interval (each interval integrated directly).
    double acc = 0;
    t.values.at(0, j) = 0.0f;
    for (int i = 1; i < o.n; ++i) {
      acc += airlight_f_between(u, t.x.node(i - 1), t.x.node(i));
      t.values.at(i, j) = static_cast<float>(acc);
    }
  });
  return t;
}

FogTable h_table(const TableOptions& o) {
  FogTable t = empty_vu_table("H", o);
  tbb::parallel_for(0, o.n, [&](int j) {
    const double u = t.y.node(j);
    for (int i = 0; i < o.n; ++i) {
      const double v = t.x.node(i);
      // K = H (1 + u tan v); it vanishes at v = π/2 as π/2 - v for every u.
      const double k = i + 1 == o.n ? 0.0 : airlight_h(u, v) * h_scale(u, v);
      t.values.at(i, j) = static_cast<float>(k);
    }
  });
  return t;
}

double h_scale(double u, double v) { return 1 + u * std::tan(v); }

double h_scale_along(double kt, double h, double z) {
  const double d = std::hypot(h, z);
  return 1 + kt * (z >= 0 ? z + d : h * h / (d - z));
}

HRow h_row(const FogTable& t, double u) {
  HRow r;
  // Beyond u_max K is continued as K(u_max, v): K tends to a function of v alone as u grows.
  r.index = t.y.index(std::min(u, t.y.hi), r.clamped);
  if (u > t.y.hi) r.clamped = true;
  return r;
}

double h_lookup(const FogTable& t, const HRow& row, double v, double scale, bool* clamped) {
  if (v >= 0.5 * kPi) return 0.0;
  bool c = row.clamped;
  const double k = sample_bilinear_inside(t.values, t.x.index(v, c), row.index);
  if (clamped && c) *clamped = true;
  return k / scale;
}

double h_lookup(const FogTable& t, double u, double v, bool* clamped) {
  return h_lookup(t, h_row(t, u), v, h_scale(u, v), clamped);
}

double ring_weight(int n, double phi, double theta) {
  if (n < 1 || n > kMaxExponent)
    throw InvariantError(fmt::format("ring_weight: exponent {} outside [1, {}]", n, kMaxExponent));
  const double a = std::cos(phi) * std::cos(theta), b = std::abs(std::sin(phi) * std::sin(theta));
  if (a >= b) {  // the whole ring lies in the hemisphere: 2π·(mean of (a + b cos ψ)^n)
    if (b == 0) return 2 * kPi * std::pow(a, n);
  } else if (a <= -b) {
    return 0.0;
  }
  // ψ0: where a + b cos ψ = 0 (π if the ring is inside); W = 2 Σ_k C(n,k) a^{n-k} b^k J_k(ψ0),
  // J_k = ∫_0^{ψ0} cos^k ψ dψ by J_k = cos^{k-1}ψ0 sin ψ0 / k + (k-1)/k J_{k-2}. Every term is
  // bounded by C(n,k)|a|^{n-k} b^k and Σ = (|a| + b)^n <= 1: the rounding error is absolute, < n·1e-16.
  const double psi0 = a >= b ? kPi : std::acos(std::clamp(-a / b, -1.0, 1.0));
  const double c0 = std::cos(psi0), s0 = std::sin(psi0);
  // a^{n-k} for k = 0..n (a may be negative: integer powers by products).
  double apow[kMaxExponent + 1];
  apow[n] = 1.0;
  for (int k = n - 1; k >= 0; --k) apow[k] = apow[k + 1] * a;
  double j_prev = psi0, j_cur = s0;  // J_0, J_1
  double binom = 1.0;                // C(n, k)
  double bpow = 1.0;                 // b^k
  double sum = apow[0] * j_prev;
  double cpow = 1.0;  // cos^{k-1} ψ0
  for (int k = 1; k <= n; ++k) {
    if (k >= 2) {
      cpow *= c0;
      const double j_next = cpow * s0 / k + (k - 1.0) / k * j_prev;
      j_prev = j_cur;
      j_cur = j_next;
    }
    binom = binom * (n - k + 1) / k;
    bpow *= b;
    sum += binom * apow[k] * bpow * j_cur;
  }
  return 2 * sum;
}

double surface_g(int n, double T, double theta) {
  if (n < 1) throw InvariantError(fmt::format("surface_g: exponent {} < 1", n));
  std::vector<double> edges;
  add_kinks(theta, edges);
  const PhiRule r = phi_rule(edges);
  double sum = 0;
  for (std::size_t k = 0; k < r.phi.size(); ++k)
    sum += r.weight[k] * g_kernel(T, r.phi[k]) * ring_weight(n, r.phi[k], theta);
  return sum;
}

FogTable g_table(int n, const TableOptions& o) {
  if (o.n < 2) throw InputError(fmt::format("fsa.table.N = {}: at least 2 nodes per axis", o.n));
  if (!(o.t_max > 0)) throw InputError(fmt::format("fsa.table.G.t_max = {}: must be > 0", o.t_max));
  FogTable t;
  t.name = fmt::format("G{}", n);
  t.x = make_axis("T", 0.0, o.t_max, o.n, o.t_warp);
  t.y = make_axis("theta", 0.0, kPi, o.n, AxisWarp::kNone);
  t.values = ImageF(o.n, o.n, 1);
  std::vector<double> edges;
  for (int j = 0; j < o.n; ++j) add_kinks(t.y.node(j), edges);
  const PhiRule r = phi_rule(edges);
  // W_n at every (φ node, θ node): shared by all rows.
  std::vector<double> w(r.phi.size() * static_cast<std::size_t>(o.n));
  tbb::parallel_for(0, o.n, [&](int j) {
    const double theta = t.y.node(j);
    for (std::size_t k = 0; k < r.phi.size(); ++k)
      w[static_cast<std::size_t>(j) * r.phi.size() + k] = r.weight[k] * ring_weight(n, r.phi[k], theta);
  });
  tbb::parallel_for(0, o.n, [&](int i) {
    const double T = t.x.node(i);
    std::vector<double> kernel(r.phi.size());
    for (std::size_t k = 0; k < r.phi.size(); ++k) kernel[k] = g_kernel(T, r.phi[k]);
    for (int j = 0; j < o.n; ++j) {
      const double* wj = w.data() + static_cast<std::size_t>(j) * r.phi.size();
      double sum = 0;
      for (std::size_t k = 0; k < r.phi.size(); ++k) sum += wj[k] * kernel[k];
      t.values.at(i, j) = static_cast<float>(sum);
    }
  });
  return t;
}

}  // namespace meltlab::render::fog
