// Seed 002's airlight and surface terms (fog/airlight.h).

#include <meltlab/render/fog/airlight.h>

#include <meltlab/core/error.h>
#include <meltlab/render/fog/airlight_f.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace meltlab::render::fog {

namespace {

constexpr double kPi = std::numbers::pi;

double table_f(const FogTable& t, double u, double v, LookupCounts* counts) {
  bool clamped = false;
  const double f = t.lookup(v, u, &clamped);
  if (counts) {
    ++counts->lookups;
    if (clamped) ++counts->clamped;
  }
  return f;
}

// H at (u, v) from the table (fog_tables.h's h_lookup: K / h_scale, K continued beyond u_max),
// u as its row.
double table_h(const FogTable& t, const HRow& row, double v, double scale, LookupCounts* counts) {
  bool clamped = false;
  const double h = h_lookup(t, row, v, scale, &clamped);
  if (counts) {
    ++counts->lookups;
    if (clamped) ++counts->clamped;
  }
  return h;
}

double g_value(const FogTable* table, int exponent, double T, double theta, LookupCounts* counts) {
  if (!table) return surface_g(exponent, T, theta);
  bool clamped = false;
  const double g = table->lookup(T, theta, &clamped);
  if (counts) {
    ++counts->lookups;
    if (clamped) ++counts->clamped;
  }
  return g;
}

// Ω k_t e^{-k_t t}/(2π h) · ΔF without overflowing when the light is far behind the eye
// (e^{-k_t t} huge, ΔF tiny).
double scaled(const RayLight& g, const FogMedium& medium, double dF) {
  if (!(dF > 0)) return 0.0;
  return medium.albedo * medium.kt / (2 * kPi * g.h) * std::exp(-medium.kt * g.t + std::log(dF));
}

}  // namespace

double Spotlight::intensity_at(double theta) const {
  if (kind == LightKind::kPoint) return 1.0;
  for (const ConeStep& s : profile)
    if (theta <= s.half_angle_rad) return s.intensity;
  return 0.0;
}

double Spotlight::intensity_at(const Vec3& x) const { return PreparedLight(*this).intensity_at(x); }

PreparedLight::PreparedLight(const Spotlight& l) : light(l), axis(l.axis.normalized()) {
  cos_half.reserve(l.profile.size());
  weight.reserve(l.profile.size());
  for (std::size_t k = 0; k < l.profile.size(); ++k) {
    cos_half.push_back(std::cos(l.profile[k].half_angle_rad));
    weight.push_back(l.profile[k].intensity - (k + 1 < l.profile.size() ? l.profile[k + 1].intensity : 0.0));
  }
}

double PreparedLight::intensity_at(const Vec3& x) const {
  if (light.kind == LightKind::kPoint) return 1.0;
  // The same test as the cones' (inside_cone: D̂·d >= cos θ_k |d|, the same operations), ring
  // by ring, so that the surface and the airlight agree on the cone's edge.
  const Vec3 d = x - light.position;
  const double n = d.norm();
  if (n == 0) return light.profile.empty() ? 0.0 : light.profile.front().intensity;
  const double along = axis.dot(d);
  for (std::size_t k = 0; k < cos_half.size(); ++k)
    if (along >= cos_half[k] * n) return light.profile[k].intensity;
  return 0.0;
}

std::vector<PreparedLight> prepare_lights(const std::vector<Spotlight>& lights) {
  return {lights.begin(), lights.end()};
}

RayLight ray_light(const Vec3& V, const Vec3& S, double h_min_rel) {
  RayLight g;
  g.l = S.norm();
  g.t = S.dot(V);
  g.h = std::max(S.cross(V).norm(), h_min_rel * g.l);
  return g;
}

double airlight_v(const RayLight& g, double x) {
  if (std::isinf(x)) return x > 0 ? 0.5 * kPi : 0.0;
  return 0.25 * kPi + 0.5 * std::atan((x - g.t) / g.h);
}

double airlight_interval(const RayLight& g, const FogMedium& medium, double a, double b, const FogFunctions& fn,
                         LookupCounts* counts) {
  if (!(b > a) || !(medium.kt > 0) || !(g.h > 0)) return 0.0;
  const double u = medium.kt * g.h;
  const double va = airlight_v(g, a), vb = airlight_v(g, b);
  if (fn.h) {
    const double kt = medium.kt;
    const HRow row = h_row(*fn.h, u);  // one row for both ends (same u)
    auto term = [&](double x, double v) {
      if (std::isinf(x)) return 0.0;
      const double z = x - g.t, d = std::hypot(g.h, z);
      return std::exp(-kt * (x + d)) * table_h(*fn.h, row, v, h_scale_along(kt, g.h, z), counts);
    };
    const double diff = term(a, va) - term(b, vb);
    return diff > 0 ? medium.albedo * kt / (2 * kPi * g.h) * diff : 0.0;
  }
  const double dF =
      fn.f ? table_f(*fn.f, u, vb, counts) - table_f(*fn.f, u, va, counts) : airlight_f_between(u, va, vb);
  return scaled(g, medium, dF);
}

double airlight_unit(const Vec3& origin, const Vec3& V, double m, const Spotlight& light, const FogMedium& medium,
                     const FogFunctions& fn, const FogModelOptions& o, LookupCounts* counts) {
  return airlight_unit(origin, V, m, PreparedLight(light), medium, fn, o, counts);
}

double airlight_unit(const Vec3& origin, const Vec3& V, double m, const PreparedLight& light, const FogMedium& medium,
                     const FogFunctions& fn, const FogModelOptions& o, LookupCounts* counts) {
  if (!(m > 0) || !(medium.kt > 0)) return 0.0;
  const Vec3 S = light.light.position - origin;
  if (light.light.kind == LightKind::kPoint)
    return airlight_interval(ray_light(V, S, o.h_min_rel), medium, 0.0, m, fn, counts);
  // The ray's light geometry only once a cone lights part of the ray (most pixels of a scene see
  // no cone, or not every one).
  RayLight g;
  bool have_g = false;
  Cone cone;
  cone.apex = S;
  cone.axis = light.axis;
  double sum = 0;
  for (std::size_t k = 0; k < light.cos_half.size(); ++k) {
    const double weight = light.weight[k];
    if (weight == 0) continue;
    cone.cos_half = light.cos_half[k];
    if (o.cone_solver == ConeSolver::kSource) {
      const Interval s = segment_in_cone_source(V, m, cone);
      // The listing's F(v_b) - F(v_a) as it comes (negative when its a > b).
      if (s.b != s.a) {
        if (!have_g) g = ray_light(V, S, o.h_min_rel), have_g = true;
        const double sign = s.b > s.a ? 1.0 : -1.0;
        sum += weight * sign * airlight_interval(g, medium, std::min(s.a, s.b), std::max(s.a, s.b), fn, counts);
      }
      continue;
    }
    const ConeSegments seg = segment_in_cone(V, m, cone);
    if (seg.count > 0 && !have_g) g = ray_light(V, S, o.h_min_rel), have_g = true;
    for (int i = 0; i < seg.count; ++i)
      sum += weight * airlight_interval(g, medium, seg.parts[static_cast<std::size_t>(i)].a,
                                        seg.parts[static_cast<std::size_t>(i)].b, fn, counts);
  }
  return sum;
}

double airlight_point_sun(const Vec3& origin, const Vec3& V, double m, const Vec3& light_position,
                          const FogMedium& medium, const FogFunctions& fn, double h_min_rel) {
  if (!(m > 0) || !(medium.kt > 0)) return 0.0;
  const Vec3 S = light_position - origin;
  const double l = S.norm();
  // φ by atan2 (acos loses half the digits for rays nearly through the light).
  const double phi = std::atan2(S.cross(V).norm(), S.dot(V));
  RayLight g;
  g.l = l;
  g.t = l * std::cos(phi);
  g.h = std::max(l * std::sin(phi), h_min_rel * l);
  const double u = medium.kt * g.h;
  const double vm = airlight_v(g, m), v0 = 0.5 * phi;
  const double dF = fn.f ? fn.f->lookup(vm, u) - fn.f->lookup(v0, u) : airlight_f_between(u, v0, vm);
  return scaled(g, medium, dF);
}

SurfaceTerms surface_terms(const Vec3& p, const Vec3& N, const Vec3& view_dir, const Spotlight& light,
                           const FogMedium& medium, const FogMaterial& mat, const FogFunctions& fn,
                           const FogModelOptions& o, LookupCounts* counts) {
  return surface_terms(p, N, view_dir, PreparedLight(light), medium, mat, fn, o, counts);
}

SurfaceTerms surface_terms(const Vec3& p, const Vec3& N, const Vec3& view_dir, const PreparedLight& prepared,
                           const FogMedium& medium, const FogMaterial& mat, const FogFunctions& fn,
                           const FogModelOptions& o, LookupCounts* counts) {
  SurfaceTerms s;
  const Spotlight& light = prepared.light;
  const Vec3 d = light.position - p;
  const double l = d.norm();
  if (!(l > 0)) return s;
  const Vec3 L = d / l;
  const double i_here = prepared.intensity_at(p);
  if (o.surface_only_in_cone && i_here == 0) return s;
  // Outside the cone (only_in_cone off) the fog term still sees the cone's intensity.
  const double i_fog = (i_here > 0 || light.profile.empty()) ? i_here : light.profile.front().intensity;
  double cos_s = std::clamp(N.dot(L), -1.0, 1.0);
  const Vec3 R = view_dir - 2 * view_dir.dot(N) * N;
  double cos_sp = std::clamp(R.dot(L), -1.0, 1.0);
  if (o.specular_args == SpecularArgs::kSource) cos_sp = std::max(0.0, cos_s);  // Specular(.., NdotL, thetas, ..)
  const double kt = medium.kt;
  const double att = std::exp(-kt * l) / (l * l);
  if (o.surface_direct) {
    s.direct_diffuse = mat.kd * i_here * att * std::max(0.0, cos_s);
    s.direct_specular = mat.ks * i_here * att * (cos_sp > 0 ? std::pow(cos_sp, mat.n) : 0.0);
  }
  if (o.surface_fog && kt > 0 && i_fog > 0) {
    const double T = kt * l;
    const double pre = i_fog * medium.albedo * kt / (2 * kPi * l);
    const double theta_s = std::acos(cos_s);
    const double theta_sp = o.specular_args == SpecularArgs::kSource ? theta_s : std::acos(cos_sp);
    if (mat.kd != 0) s.fog_diffuse = mat.kd * pre * g_value(fn.g_diffuse, 1, T, theta_s, counts);
    if (mat.ks != 0) s.fog_specular = mat.ks * pre * g_value(fn.g_specular, mat.n, T, theta_sp, counts);
  }
  return s;
}

Rgb fog_radiance(const Vec3& origin, const Vec3& V, double m, const SurfaceHit* surface,
                 const std::vector<Spotlight>& lights, const FogMedium& medium, const FogFunctions& fn,
                 const FogModelOptions& o, LookupCounts* counts) {
  return fog_radiance(origin, V, m, surface, prepare_lights(lights), medium, fn, o, counts);
}

Rgb fog_radiance(const Vec3& origin, const Vec3& V, double m, const SurfaceHit* surface,
                 const std::vector<PreparedLight>& lights, const FogMedium& medium, const FogFunctions& fn,
                 const FogModelOptions& o, LookupCounts* counts) {
  Rgb out = Rgb::Zero();
  const double view_att =
      o.view_attenuation == ViewAttenuation::kApply && std::isfinite(m) ? std::exp(-medium.kt * m) : 1.0;
  for (const PreparedLight& prepared : lights) {
    const Spotlight& light = prepared.light;
    const Rgb I = light.colour * light.intensity;
    double air = 0;
    if (o.airlight) air = airlight_unit(origin, V, m, prepared, medium, fn, o, counts);
    Rgb c = Rgb::Constant(air);
    if (surface && surface->material && (o.surface_direct || o.surface_fog)) {
      const SurfaceTerms s =
          surface_terms(surface->p, surface->normal, V, prepared, medium, *surface->material, fn, o, counts);
      c += view_att * (s.diffuse() * surface->material->diffuse_colour + Rgb::Constant(s.specular()));
    }
    out += c.cwiseProduct(I);
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> describe_options(const FogModelOptions& o) {
  return {
      {"fsa.phase.normalisation", "normalised p (1/(4π) isotropic), no extra 1/(4π)"},
      {"fsa.phase.function", "isotropic (HG only in R-air)"},
      {"fsa.light.cone_edge", "hard"},
      {"fsa.brdf.lambert_norm", "kd (no 1/π)"},
      {"fsa.surface.ab_assumption", "a = 0, b = ∞ (R-surf-true measures it)"},
      {"fsa.errata.eq31_integrand", "L(x, ω_i)"},
      {"fsa.surface.view_attenuation", o.view_attenuation == ViewAttenuation::kApply ? "apply" : "source_omit"},
      {"fsa.cone.solver", o.cone_solver == ConeSolver::kRobust ? "robust" : "source"},
      {"fsa.errata.specular_args", o.specular_args == SpecularArgs::kMirror ? "mirror" : "source"},
      {"fsa.surface.only_in_cone", o.surface_only_in_cone ? "true" : "false"},
      {"fsa.h_min", fmt::format("{} l", o.h_min_rel)},
      {"terms",
       fmt::format("airlight {}, surface direct {}, surface fog {}", o.airlight, o.surface_direct, o.surface_fog)},
  };
}

}  // namespace meltlab::render::fog
