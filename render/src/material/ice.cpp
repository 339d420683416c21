// The ice materials: the monograph's (Eq. 6.11, 6.12) and the physical reference (material/ice.h).

#include <meltlab/render/material/ice.h>
#include <meltlab/core/error.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <optional>

namespace meltlab::render {

using Eigen::Vector3d;

namespace {

// Physical model: an internally reflected path is dropped once its weight falls below this
// (the bias is below 1e-4 of the radiance it would carry, far under 8-bit quantisation).
constexpr double kMinPathWeight = 1e-4;

// Orthonormal tangent frame for the triplanar normal map: the projection axis is the dominant
// axis of `ng`; tangent and bitangent are the other two world axes made orthogonal to `n`.
void tangent_frame(const Vector3d& n, const Vector3d& ng, Vector3d& t, Vector3d& b, int& axis) {
  axis = dominant_axis(ng);
  const Vector3d u = axis == 0 ? Vector3d::UnitY() : Vector3d::UnitX();
  t = (u - n * n.dot(u)).normalized();
  b = n.cross(t);
}

}  // namespace

IcePlan plan_ice(const IceMaterial& m, bool lit, std::vector<std::string>& skipped) {
  IcePlan p;
  auto skip = [&](bool& flag, bool keep, const std::string& why) {
    flag = keep;
    if (!keep) skipped.push_back(why);
  };
  if (m.model == IceModel::kMonograph) {
    skip(p.ice_texture, m.ca > 0 || m.cd > 0, "ice texture and diffuse (ca = cd = 0)");
    skip(p.ice_specular, m.cs > 0 && lit, "ice specular (cs = 0 or no light)");
    skip(p.ice_reflection, m.cr > 0, "ice environment reflection (cr = 0)");
    skip(p.ice_transmission, m.ct > 0, "ice refraction and dispersion (ct = 0)");
    skip(p.fresnel, p.ice_reflection || p.ice_transmission, "Fresnel (cr = ct = 0)");
  } else {
    p.ice_texture = p.ice_specular = false;
    p.ice_reflection = p.ice_transmission = p.fresnel = true;
  }
  const bool distinct_eta = m.eta_rgb[0] != m.eta_rgb[1] || m.eta_rgb[1] != m.eta_rgb[2];
  if (p.ice_transmission)
    skip(p.dispersion, m.dispersion && distinct_eta, "dispersion (off or equal indices: one refraction)");
  else
    p.dispersion = false;
  p.normal_map = m.normal_map;
  return p;
}

IceShader::IceShader(const IceMaterial& material, const IcePlan& plan, const IceTextures& textures)
    : material_(material), plan_(plan), textures_(textures) {
  if (!textures_.environment) throw InvariantError("IceShader: no environment texture");
  if (plan_.normal_map && !textures_.normal_map) throw InvariantError("IceShader: no normal-map texture");
}

Vector3d IceShader::facing_normal(const SurfaceHit& hit, const Vector3d& V, const Differential* dp,
                                  Differential* dN) const {
  Vector3d n = hit.n;
  if (dp) *dN = hit.dn;
  if (plan_.normal_map) {
    Vector3d t, b;
    int axis = 2;
    tangent_frame(n, hit.ng, t, b, axis);
    const Rgb enc = lookup_projected(*textures_.normal_map, hit.p, axis, material_.normal_map_tile, dp);
    const Vector3d nm = 2.0 * (enc - Rgb::Constant(0.5));  // Eq. 6.12
    n = (nm.x() * t + nm.y() * b + nm.z() * n).normalized();
  }
  if (n.dot(V) < 0) {  // face the eye (back faces seen from inside, bent normals)
    n = -n;
    if (dp) *dN = {-dN->dx, -dN->dy};
  }
  return n;
}

// ---- the monograph's ice (Eq. 6.11) ----

MonographIce::MonographIce(const IceMaterial& material, const IcePlan& plan, const IceTextures& textures,
                           const std::vector<Light>& lights)
    : IceShader(material, plan, textures), lights_(lights) {}

Rgb MonographIce::tdiff(const SurfaceHit& hit, const Differential* dp) const {
  if (!textures_.image) return Rgb::Constant(milky_ice(hit.p, material_.texture_scale));
  return lookup_projected(*textures_.image, hit.p, dominant_axis(hit.ng), material_.texture_tile, dp);
}

Rgb MonographIce::shade(const SurfaceHit& hit, const Vector3d& d, const RayDifferential* rd) const {
  const IceMaterial& m = material_;
  const Vector3d V = -d.normalized();
  Differential dN;
  const Vector3d N = facing_normal(hit, V, rd ? &rd->o : nullptr, &dN);
  Rgb I = Rgb::Zero();
  // Eq. 6.11's Phong part: (ca + Σ Izr·cd·max(0, N·L))·tdiff + Σ Izr·cs·max(0, Rs·V)^n.
  if (plan_.ice_texture || plan_.ice_specular) {
    Rgb diffuse = Rgb::Constant(m.ca), spec = Rgb::Zero();
    for (const Light& light : lights_) {
      const Vector3d& L = light.to_light;
      const Rgb& Izr = light.colour;
      if (plan_.ice_texture) diffuse += Izr * m.cd * std::max(0.0, N.dot(L));
      if (plan_.ice_specular) {
        const Vector3d Rs = reflect(L, N);
        const double x = m.specular == SpecularTerm::kRsV ? Rs.dot(V) : Rs.dot(L);
        spec += Izr * m.cs * pow_pos(x, m.n_spec);
      }
    }
    if (plan_.ice_texture) I += diffuse.cwiseProduct(tdiff(hit, rd ? &rd->o : nullptr));
    I += spec;
  }
  if (!plan_.fresnel) return I;
  // Eq. 6.11's environment part: cr·F·tenv(Re) + ct·(1 - F)·tenv(T), Re by Eq. 6.3, T by Eq. 6.7
  // (per channel, Eq. 6.8), F by Eq. 6.9 or 6.10.
  const EnvironmentTexture& env = *textures_.environment;
  const double cos_i = std::clamp(N.dot(V), 0.0, 1.0);
  const double eta_ice = plan_.dispersion ? m.eta_rgb[1] : m.eta;
  const double F = fresnel(m.fresnel, cos_i, 1.0, eta_ice);
  if (plan_.ice_reflection) {
    const Differential dR = rd ? reflected_footprint(V, rd->d, N, dN) : Differential{};
    I += m.cr * F * env.lookup(reflect(V, N), rd ? &dR : nullptr);
  }
  if (plan_.ice_transmission) {
    auto seen_through = [&](double eta_rel) -> std::optional<Rgb> {
      const auto T = refract(-V, N, eta_rel);
      if (!T) return std::nullopt;
      if (!rd) return env.lookup(*T, nullptr);
      const Differential dT{refract_differential(-V, rd->d.dx, N, dN.dx, eta_rel),
                            refract_differential(-V, rd->d.dy, N, dN.dy, eta_rel)};
      return env.lookup(*T, &dT);
    };
    if (plan_.dispersion) {
      for (int c = 0; c < 3; ++c)
        if (const auto L = seen_through(1.0 / m.eta_rgb[static_cast<std::size_t>(c)])) I[c] += m.ct * (1 - F) * (*L)[c];
    } else if (const auto L = seen_through(1.0 / m.eta)) {
      I += m.ct * (1 - F) * *L;
    }
  }
  return I;
}

// ---- the physical reference ----

PhysicalIce::PhysicalIce(const IceMaterial& material, const IcePlan& plan, const IceTextures& textures,
                         const IceSurroundings& surroundings, double offset)
    : IceShader(material, plan, textures), surroundings_(surroundings), offset_(offset) {}

Rgb PhysicalIce::shade(const SurfaceHit& hit, const Vector3d& d, const RayDifferential* rd) const {
  const IceMaterial& m = material_;
  const double eps = offset_;
  const Vector3d& p = hit.p;
  const Vector3d V = -d.normalized();
  Differential dN;
  const Vector3d N = facing_normal(hit, V, rd ? &rd->o : nullptr, &dN);
  const double cos_i = std::clamp(N.dot(V), 0.0, 1.0);
  Rgb I = Rgb::Zero();
  const int channels = plan_.dispersion ? 3 : 1;
  // Reflection with each channel's own Fresnel weight, so that reflected + transmitted = 1
  // per channel (the white-furnace test checks this bookkeeping). Only the mirrored ray
  // carries a footprint; the paths through the ice look up the finest level.
  const RayDifferential mirror = rd ? RayDifferential{rd->o, reflected_footprint(V, rd->d, N, dN)} : RayDifferential{};
  const Rgb from_mirror = surroundings_.radiance_outside(p + eps * N, reflect(V, N), rd ? &mirror : nullptr);
  if (!plan_.dispersion) I += fresnel(m.fresnel, cos_i, 1.0, m.eta) * from_mirror;
  for (int c = 0; c < channels; ++c) {
    const double eta = plan_.dispersion ? m.eta_rgb[static_cast<std::size_t>(c)] : m.eta;
    const double F = fresnel(m.fresnel, cos_i, 1.0, eta);
    if (plan_.dispersion) I[c] += F * from_mirror[c];
    const auto T = refract(-V, N, 1.0 / eta);
    if (!T) continue;
    // Through the ice: Beer absorption to each exit, the refracted part out, the reflected part on.
    Vector3d dir = *T, o = p - eps * N;
    Rgb weight = Rgb::Constant(1 - F);
    for (int bounce = 0; bounce <= m.max_internal_bounces; ++bounce) {
      const std::optional<SurfaceCrossing> e = surroundings_.next_crossing(o, dir, eps);
      if (!e) {  // leaked through a crack: see the environment
        const Rgb L = textures_.environment->lookup(dir, nullptr);
        if (plan_.dispersion)
          I[c] += weight[c] * L[c];
        else
          I += weight.cwiseProduct(L);
        break;
      }
      for (int k = 0; k < 3; ++k) weight[k] *= std::exp(-m.absorption[static_cast<std::size_t>(k)] * e->t);
      const Vector3d q = o + e->t * dir;
      Vector3d n_out = e->n;
      if (n_out.dot(dir) < 0) n_out = -n_out;  // the normal on the far side of the interface
      const double cos_x = std::clamp(dir.dot(n_out), 0.0, 1.0);
      const double Fx = fresnel(m.fresnel, cos_x, eta, 1.0);
      const Vector3d reflected = dir - 2.0 * dir.dot(n_out) * n_out;
      if (const auto out = refract(dir, -n_out, eta)) {
        const Rgb L = surroundings_.radiance_outside(q + eps * n_out, *out, nullptr);
        if (plan_.dispersion)
          I[c] += weight[c] * (1 - Fx) * L[c];
        else
          I += (1 - Fx) * weight.cwiseProduct(L);
        weight *= Fx;
      }
      dir = reflected.normalized();
      o = q - eps * n_out;
      if (weight.maxCoeff() < kMinPathWeight) break;  // what is left cannot show in the image
    }
  }
  return I;
}

}  // namespace meltlab::render
