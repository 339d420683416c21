// References of seed 002's fog model and the ray-marching peer (fog/reference.h).

#include <meltlab/render/fog/reference.h>

#include <meltlab/core/error.h>
#include <meltlab/render/fog/airlight_f.h>
#include <meltlab/render/fog/quadrature.h>

#include <boost/math/quadrature/gauss.hpp>
#include <boost/math/quadrature/tanh_sinh.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace meltlab::render::fog {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Bisection on the indicator stops when the bracket is below this relative width (or 1e-13 m
// near 0): far below the spec's 1e-9 m agreement target for the cone segment.
constexpr double kBisectRel = 1e-14;

// The relative intensity seen from the light along `d` (= X - S): the rings' test of
// Spotlight::intensity_at without normalising twice.
double ring_intensity(const Spotlight& light, const Vec3& axis, const std::vector<double>& cos_rings, const Vec3& d) {
  if (light.kind == LightKind::kPoint) return 1.0;
  const double dn = d.norm();
  const double c = axis.dot(d);
  for (std::size_t k = 0; k < cos_rings.size(); ++k)
    if (c >= cos_rings[k] * dn) return light.profile[k].intensity;
  return 0.0;
}

std::vector<double> ring_cosines(const Spotlight& light) {
  std::vector<double> c;
  for (const ConeStep& s : light.profile) c.push_back(std::cos(s.half_angle_rad));
  return c;
}

double phase(double g, double cos_alpha) {
  if (g == 0) return 1.0 / (4 * kPi);
  const double den = 1 + g * g - 2 * g * cos_alpha;
  return (1 - g * g) / (4 * kPi * den * std::sqrt(den));
}

// Bisection of [lo, hi] (finite) where inside(lo) != inside(hi): the crossing.
template <class Inside>
double bisect(Inside inside, double lo, double hi) {
  const bool at_lo = inside(lo);
  for (int it = 0; it < 400; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (hi - lo <= kBisectRel * std::max(1e1 * kBisectRel, std::abs(mid)) || mid == lo || mid == hi) break;
    (inside(mid) == at_lo ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

template <int N>
void gauss_legendre(std::vector<double>& x, std::vector<double>& w) {
  using GL = boost::math::quadrature::gauss<double, N>;
  x.clear();
  w.clear();
  for (std::size_t k = 0; k < GL::abscissa().size(); ++k) {
    x.push_back(GL::abscissa()[k]);
    w.push_back(GL::weights()[k]);
    if (GL::abscissa()[k] != 0) {
      x.push_back(-GL::abscissa()[k]);
      w.push_back(GL::weights()[k]);
    }
  }
}

void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  switch (n) {
    case 64:
      return gauss_legendre<64>(x, w);
    case 128:
      return gauss_legendre<128>(x, w);
    case 256:
      return gauss_legendre<256>(x, w);
    case 512:
      return gauss_legendre<512>(x, w);
    case 1024:
      return gauss_legendre<1024>(x, w);
    case 2048:
      return gauss_legendre<2048>(x, w);
    default:
      throw InvariantError(fmt::format("surface reference: no Gauss–Legendre rule of {} points", n));
  }
}

// An orthonormal frame (e1, e2, pole).
void frame_around(const Vec3& pole, Vec3& e1, Vec3& e2) {
  const Vec3 a = std::abs(pole.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  e1 = (a - pole * pole.dot(a)).normalized();
  e2 = pole.cross(e1);
}

// The hemisphere quadrature shared by both surface references: La(φ, ψ, ω) gives the airlight
// per unit intensity along ω; the BRDF factors kd max(0, ω·N) and ks max(0, ω·A)^n.
template <class LaFn>
SurfRefResult hemisphere_quadrature(const Vec3& N, const Vec3& spec_axis, const Vec3& to_light, const FogMaterial& mat,
                                    const SurfRefOptions& o, bool la_depends_on_psi, LaFn la) {
  Vec3 e1, e2;
  frame_around(to_light, e1, e2);
  SurfRefResult r;
  double prev = kInf;
  for (int n_phi = o.n_phi, n_psi = o.n_psi; n_phi <= o.max_n_phi; n_phi *= 2, n_psi *= 2) {
    std::vector<double> x, w;
    gauss_legendre(n_phi, x, w);
    double diff = 0, spec = 0;
    const double dpsi = 2 * kPi / n_psi;
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double phi = 0.5 * kPi * (x[i] + 1), wphi = 0.5 * kPi * w[i];
      const double sp = std::sin(phi), cp = std::cos(phi);
      double la_ring = 0;
      if (!la_depends_on_psi) la_ring = la(phi, 0.0, Vec3(sp * e1 + cp * to_light));
      double d_sum = 0, s_sum = 0;
      for (int j = 0; j < n_psi; ++j) {
        const double psi = (j + 0.5) * dpsi;
        const Vec3 omega = sp * std::cos(psi) * e1 + sp * std::sin(psi) * e2 + cp * to_light;
        const double cd = mat.kd != 0 ? std::max(0.0, omega.dot(N)) : 0.0;
        const double cs = mat.ks != 0 ? std::max(0.0, omega.dot(spec_axis)) : 0.0;
        if (cd == 0 && cs == 0) continue;
        const double L = la_depends_on_psi ? la(phi, psi, omega) : la_ring;
        d_sum += L * cd;
        s_sum += L * (cs > 0 ? std::pow(cs, mat.n) : 0.0);
      }
      diff += wphi * sp * dpsi * d_sum;
      spec += wphi * sp * dpsi * s_sum;
    }
    r.terms.fog_diffuse = mat.kd * diff;
    r.terms.fog_specular = mat.ks * spec;
    r.n_phi = n_phi;
    r.n_psi = n_psi;
    const double total = r.terms.fog_diffuse + r.terms.fog_specular;
    r.last_change = std::isfinite(prev) ? std::abs(total - prev) / std::max(std::abs(total), 1e-300) : kInf;
    if (r.last_change <= o.rel_change) break;
    prev = total;
  }
  return r;
}

}  // namespace

std::vector<double> indicator_crossings(const Vec3& origin, const Vec3& V, double m, const Vec3& light_position,
                                        const Vec3& axis_in, double half_angle_rad) {
  std::vector<double> out;
  const Vec3 S = light_position - origin;
  const Vec3 D = axis_in.normalized();
  const double cos_c = std::cos(half_angle_rad);
  auto inside = [&](double x) {
    const Vec3 d = x * V - S;
    return D.dot(d) >= cos_c * d.norm();
  };
  const double t = S.dot(V);
  const Vec3 foot = t * V - S;
  const double h = foot.norm();
  // The maximum of D̂·(X - S)/|X - S| along the line: at β* = atan2(D̂·V̂, D̂·n̂) where the
  // direction from S is cos β n̂ + sin β V̂ and x = t + h tan β.
  double x_star;
  if (h <= 1e-300) {
    x_star = t;  // the ray through the apex: constant on either side of it
  } else {
    const Vec3 n = foot / h;
    const double beta = std::atan2(D.dot(V), D.dot(n));
    if (beta >= 0.5 * kPi)
      x_star = kInf;
    else if (beta <= -0.5 * kPi)
      x_star = -kInf;
    else
      x_star = t + h * std::tan(beta);
  }
  const double split = std::clamp(x_star, 0.0, m);
  const bool at_inf = D.dot(V) >= cos_c;  // the indicator's limit as x -> ∞
  for (auto [lo, hi] : {std::pair{0.0, split}, std::pair{split, m}}) {
    if (!(hi > lo)) continue;
    const bool in_lo = inside(lo);
    bool in_hi;
    double hi_finite = hi;
    if (std::isinf(hi)) {
      in_hi = at_inf;
      if (in_lo == in_hi) continue;
      hi_finite = std::max(1.0, 2 * std::abs(lo));
      for (int k = 0; k < 1100 && inside(hi_finite) != in_hi; ++k) hi_finite *= 2;
      if (inside(hi_finite) != in_hi) continue;
    } else {
      in_hi = inside(hi);
    }
    if (in_lo == in_hi) continue;
    out.push_back(bisect(inside, lo, hi_finite));
  }
  std::sort(out.begin(), out.end());
  return out;
}

RairResult r_air(const Vec3& origin, const Vec3& V, double m, const Spotlight& light, const FogMedium& medium,
                 const RairOptions& o) {
  RairResult r;
  if (!(m > 0) || !(medium.kt > 0)) {
    r.knots = {0.0, m};
    return r;
  }
  const Vec3 S = light.position - origin;
  const Vec3 D = light.axis.normalized();
  const std::vector<double> cos_rings = ring_cosines(light);
  const double kt = medium.kt, pre = medium.albedo * kt;
  auto f = [&](double x) -> double {
    if (std::isinf(x)) return 0.0;
    const Vec3 d = x * V - S;
    const double d2 = d.squaredNorm();
    const double I = ring_intensity(light, D, cos_rings, d);
    if (I == 0 || d2 == 0) return 0.0;
    const double dn = std::sqrt(d2);
    return pre * phase(o.hg_g, -d.dot(V) / dn) * I * std::exp(-kt * (dn + x)) / d2;
  };
  r.knots = {0.0, m};
  const double t = S.dot(V);
  if (t > 0 && t < m) r.knots.push_back(t);
  if (light.kind == LightKind::kSpot)
    for (const ConeStep& s : light.profile)
      for (double c : indicator_crossings(origin, V, m, light.position, D, s.half_angle_rad)) {
        r.crossings.push_back(c);
        r.knots.push_back(c);
      }
  std::sort(r.crossings.begin(), r.crossings.end());
  std::sort(r.knots.begin(), r.knots.end());
  boost::math::quadrature::tanh_sinh<double> ts;
  double gk = 0, confirm = 0;
  for (std::size_t i = 0; i + 1 < r.knots.size(); ++i) {
    const double lo = r.knots[i], hi = r.knots[i + 1];
    if (!(hi > lo)) continue;
    const double mid = std::isinf(hi) ? 2 * lo + 1 : 0.5 * (lo + hi);
    const Vec3 dm = mid * V - S;
    if (light.kind == LightKind::kSpot && ring_intensity(light, D, cos_rings, dm) == 0) continue;
    if (std::isfinite(hi)) {
      gk += integrate_gk(f, lo, hi, o.rel_tol);
    } else {  // x = lo + s/(1 - s), s in [0, 1)
      gk += integrate_gk([&](double s) { return s >= 1 ? 0.0 : f(lo + s / (1 - s)) / ((1 - s) * (1 - s)); }, 0.0, 1.0,
                         o.rel_tol);
    }
    confirm += ts.integrate(f, lo, hi, o.rel_tol);
  }
  r.value = gk;
  r.confirm = confirm;
  r.accepted = std::abs(gk - confirm) <= o.accept_rel * std::max(std::abs(gk), 1e-300);
  return r;
}

double march_airlight(const Vec3& origin, const Vec3& V, double m, const Spotlight& light, const FogMedium& medium,
                      double step_m, std::int64_t* steps) {
  if (!std::isfinite(m)) throw InvariantError("march_airlight: m must be finite");
  if (!(m > 0) || !(medium.kt > 0)) return 0.0;
  const Vec3 S = light.position - origin;
  const Vec3 D = light.axis.normalized();
  const std::vector<double> cos_rings = ring_cosines(light);
  const auto n = static_cast<std::int64_t>(std::max(1.0, std::ceil(m / step_m)));
  const double dx = m / static_cast<double>(n), kt = medium.kt;
  double sum = 0;
  for (std::int64_t k = 0; k < n; ++k) {
    const double x = (static_cast<double>(k) + 0.5) * dx;
    const Vec3 d = x * V - S;
    const double I = ring_intensity(light, D, cos_rings, d);
    if (I == 0) continue;
    const double d2 = d.squaredNorm();
    sum += I * std::exp(-kt * (std::sqrt(d2) + x)) / d2;
  }
  if (steps) *steps += n;
  return medium.albedo * kt / (4 * kPi) * sum * dx;
}

namespace {

SurfaceTerms direct_terms(const Vec3& p, const Vec3& N, const Vec3& view_dir, const Spotlight& light,
                          const FogMedium& medium, const FogMaterial& mat, FogModelOptions model) {
  model.surface_fog = false;
  model.surface_direct = true;
  model.surface_only_in_cone = false;
  return surface_terms(p, N, view_dir, light, medium, mat, FogFunctions{}, model);
}

Vec3 specular_axis(const Vec3& N, const Vec3& view_dir, const FogModelOptions& model) {
  return model.specular_args == SpecularArgs::kSource ? N : Vec3(view_dir - 2 * view_dir.dot(N) * N);
}

}  // namespace

SurfRefResult r_surf_model(const Vec3& p, const Vec3& N, const Vec3& view_dir, const Spotlight& light,
                           const FogMedium& medium, const FogMaterial& mat, const FogModelOptions& model,
                           const SurfRefOptions& o) {
  SurfRefResult r;
  const double i_here = light.intensity_at(p);
  if (model.surface_only_in_cone && i_here == 0) return r;
  const double i_fog = (i_here > 0 || light.profile.empty()) ? i_here : light.profile.front().intensity;
  const SurfaceTerms direct = direct_terms(p, N, view_dir, light, medium, mat, model);
  if (medium.kt > 0 && i_fog > 0) {
    Spotlight point = light;  // the model's assumption: no cone, a = 0, b = ∞
    point.kind = LightKind::kPoint;
    const double b = o.far_mfp / medium.kt;
    const Vec3 to_light = (light.position - p).normalized();
    r = hemisphere_quadrature(
        N, specular_axis(N, view_dir, model), to_light, mat, o, false,
        [&](double, double, const Vec3& omega) { return i_fog * r_air(p, omega, b, point, medium).value; });
  }
  r.terms.direct_diffuse = model.surface_direct ? direct.direct_diffuse : 0.0;
  r.terms.direct_specular = model.surface_direct ? direct.direct_specular : 0.0;
  return r;
}

SurfRefResult r_surf_true(const Vec3& p, const Vec3& N, const Vec3& view_dir, const Spotlight& light,
                          const FogMedium& medium, const FogMaterial& mat, const OccluderFn& occluder,
                          const FogModelOptions& model, const SurfRefOptions& o) {
  SurfRefResult r;
  const SurfaceTerms direct = direct_terms(p, N, view_dir, light, medium, mat, model);
  if (medium.kt > 0) {
    const double far = o.far_mfp / medium.kt;
    const Vec3 to_light = (light.position - p).normalized();
    FogModelOptions exact = model;
    exact.cone_solver = ConeSolver::kRobust;
    r = hemisphere_quadrature(N, specular_axis(N, view_dir, model), to_light, mat, o, true,
                              [&](double, double, const Vec3& omega) {
                                const double m = occluder ? std::min(far, occluder(p, omega)) : far;
                                return airlight_unit(p, omega, m, light, medium, FogFunctions{}, exact);
                              });
  }
  r.terms.direct_diffuse = model.surface_direct ? direct.direct_diffuse : 0.0;
  r.terms.direct_specular = model.surface_direct ? direct.direct_specular : 0.0;
  return r;
}

}  // namespace meltlab::render::fog
