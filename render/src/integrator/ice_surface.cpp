// Ray tracer of melting ice on a wet ground (integrator/ice_surface.h).

#include <meltlab/render/integrator/ice_surface.h>
#include <meltlab/render/fog/scene_fog.h>
#include <meltlab/render/texture/filtered.h>
#include <meltlab/render/material/optics.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace meltlab::render {

using Eigen::Vector3d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Physical model: an internally reflected path is dropped once its weight falls below this
// (the bias is below 1e-4 of the radiance it would carry, far under 8-bit quantisation).
constexpr double kMinPathWeight = 1e-4;

// max(0, x)^e (e >= 0; 0^0 = 1 as std::pow), without calling pow for the many non-positive bases.
double pow_pos(double x, double e) { return x > 0 ? std::pow(x, e) : (e == 0 ? 1.0 : 0.0); }

// Per-channel power: x^e for x >= 0.
Rgb pow_rgb(const Rgb& x, double e) { return Rgb(pow_pos(x.x(), e), pow_pos(x.y(), e), pow_pos(x.z(), e)); }

// What the wet test (Eq. 7.7 on the bilinear mask) gives around each texel, so that the
// ground shading can skip the five bilinear tests (centre and the rim's four neighbours)
// where their outcome is known: the tests at texel coordinates within one texel of
// [i, i+1) x [j, j+1) read only texels [i-1, i+2] x [j-1, j+2], and a bilinear value is a
// convex combination of the texels it reads. kDry: all of them below p (every test is 0);
// kWet: all above p by a margin that covers the rounding of the interpolation (every test
// is 1); kMixed: evaluate. Only for a constant threshold p > 0.
enum WetWindow : std::uint8_t { kDry = 0, kWet = 1, kMixed = 2 };
constexpr double kWetMargin = 1e-6;  // relative; the interpolation rounds at ~1e-16

std::vector<std::uint8_t> wet_windows(const sim::LiquidMask& mask) {
  const auto& mp = mask.params();
  const int w = mp.width, h = mp.height;
  const auto& v = mask.values();
  const double p = mp.threshold;
  auto texel = [&](int i, int j) -> double {  // zero outside, as the shading reads it
    return (i < 0 || j < 0 || i >= w || j >= h) ? 0.0 : static_cast<double>(v[static_cast<std::size_t>(j) * w + i]);
  };
  // Separable minimum and maximum over the 4 x 4 window.
  std::vector<double> row_min(static_cast<std::size_t>(w) * (h + 3)), row_max(row_min.size());
  for (int j = -1; j <= h + 1; ++j)
    for (int i = 0; i < w; ++i) {
      double lo = kInf, hi = -kInf;
      for (int k = i - 1; k <= i + 2; ++k) {
        lo = std::min(lo, texel(k, j));
        hi = std::max(hi, texel(k, j));
      }
      const std::size_t at = static_cast<std::size_t>(j + 1) * w + i;
      row_min[at] = lo;
      row_max[at] = hi;
    }
  std::vector<std::uint8_t> out(static_cast<std::size_t>(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      double lo = kInf, hi = -kInf;
      for (int k = j - 1; k <= j + 2; ++k) {
        const std::size_t at = static_cast<std::size_t>(k + 1) * w + i;
        lo = std::min(lo, row_min[at]);
        hi = std::max(hi, row_max[at]);
      }
      out[static_cast<std::size_t>(j) * w + i] = hi < p ? kDry : (lo >= p * (1 + kWetMargin) ? kWet : kMixed);
    }
  return out;
}

// Orthonormal tangent frame for the triplanar normal map: the projection axis is the dominant
// axis of `ng`; tangent and bitangent are the other two world axes made orthogonal to `n`.
int dominant_axis(const Vector3d& ng) {
  const Vector3d a = ng.cwiseAbs();
  return a.x() > a.y() ? (a.x() > a.z() ? 0 : 2) : (a.y() > a.z() ? 1 : 2);
}
void tangent_frame(const Vector3d& n, const Vector3d& ng, Vector3d& t, Vector3d& b, int& axis) {
  axis = dominant_axis(ng);
  const Vector3d u = axis == 0 ? Vector3d::UnitY() : Vector3d::UnitX();
  t = (u - n * n.dot(u)).normalized();
  b = n.cross(t);
}

}  // namespace

IceRenderer::IceRenderer(RenderScene scene) : scene_(std::move(scene)) {
  // Image files named by the scene replace the procedural assets (read through OpenImageIO).
  env_ = scene_.environment.file.empty() ? latlong_environment(scene_.environment)
                                         : read_environment(scene_.environment.file, scene_.environment.layout);
  ground_tex_ =
      scene_.ground.texture_file.empty() ? ground_texture(256, 1) : read_rgb_image(scene_.ground.texture_file);
  if (scene_.ice.normal_map)
    normal_tex_ = scene_.ice.normal_map_file.empty() ? normal_map(256, scene_.ice.normal_map_bump, 2)
                                                     : read_rgb_image(scene_.ice.normal_map_file);
  if (!scene_.ice.texture_file.empty()) ice_tex_ = read_rgb_image(scene_.ice.texture_file);
  if (scene_.camera) camera_ = scene_.camera;
  if (scene_.fog)
    fog_ = std::make_unique<fog::FogShader>(*scene_.fog, std::vector<double>{scene_.ice.n_spec, scene_.ground.n_spec});
  if (scene_.texture_filter == TextureFilter::kMipmap) {
    filtered_ = std::make_unique<FilteredTextures>();
    env_id_ = filtered_->add(env_, FilteredTextures::Kind::kLatLongEnvironment, "environment");
    ground_id_ = filtered_->add(ground_tex_, FilteredTextures::Kind::kTexture, "ground texture");
    if (scene_.ice.normal_map) normal_id_ = filtered_->add(normal_tex_, FilteredTextures::Kind::kTexture, "normal map");
    if (!ice_tex_.empty()) ice_id_ = filtered_->add(ice_tex_, FilteredTextures::Kind::kTexture, "ice texture");
  }
}
IceRenderer::~IceRenderer() = default;

const Camera& IceRenderer::camera() const {
  if (!camera_) throw InvariantError("IceRenderer: no camera before the first set_mesh");
  return *camera_;
}

void IceRenderer::resolve_defaults() {
  if (sized_ || bvh_.empty()) return;
  sized_ = true;
  const Vector3d ext = bvh_.upper() - bvh_.lower();
  object_size_ = std::max({ext.x(), ext.y(), ext.z(), 1e-9});
  if (!(scene_.ice.texture_scale > 0)) scene_.ice.texture_scale = 0.05 * object_size_;
  if (!(scene_.ice.normal_map_tile > 0)) scene_.ice.normal_map_tile = 0.2 * object_size_;
  if (!(scene_.ice.texture_tile > 0)) scene_.ice.texture_tile = 0.2 * object_size_;
  if (!(scene_.ground.tile > 0)) scene_.ground.tile = 0.5 * object_size_;
  if (!scene_.ground.z) scene_.ground.z = bvh_.lower().z();
  if (!camera_) camera_ = auto_camera(bvh_.lower(), bvh_.upper(), scene_.width, scene_.height);
}

template <class Real>
void IceRenderer::set_mesh(const sim::TriMesh<Real>& mesh) {
  stats_.bvh = bvh_.update(mesh);
  stats_.bvh_ms = bvh_.last_update_ms();
  stats_.triangles = bvh_.triangle_count();
  resolve_defaults();
}
template void IceRenderer::set_mesh(const sim::TriMesh<double>&);
template void IceRenderer::set_mesh(const sim::TriMesh<float>&);
void IceRenderer::set_mesh(const sim::IndexedMesh& mesh) {
  stats_.bvh = bvh_.update(mesh);
  stats_.bvh_ms = bvh_.last_update_ms();
  stats_.triangles = bvh_.triangle_count();
  resolve_defaults();
}

ShadingPlan IceRenderer::plan() const {
  ShadingPlan p;
  const IceMaterial& m = scene_.ice;
  const GroundMaterial& g = scene_.ground;
  auto skip = [&](bool& flag, bool keep, const std::string& why) {
    flag = keep;
    if (!keep) p.skipped.push_back(why);
  };
  if (m.model == IceModel::kMonograph) {
    skip(p.ice_texture, m.ca > 0 || m.cd > 0, "ice texture and diffuse (ca = cd = 0)");
    skip(p.ice_specular, m.cs > 0 && !scene_.lights.empty(), "ice specular (cs = 0 or no light)");
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
  skip(p.ground_specular, g.cs > 0 && !scene_.lights.empty(), "ground specular (cs = 0 or no light)");
  const bool visible = g.a > 0 || g.cr > 0 || g.tilt_s > 0 || g.tilt_t > 0 || g.d > 0;
  if (!g.liquid)
    skip(p.liquid, false, "liquid (ground.liquid off)");
  else if (!mask_)
    skip(p.liquid, false, "liquid (no mask: sublimation or no liquid stage)");
  else if (!visible)
    skip(p.liquid, false, "liquid (a = cr = tilt = d = 0)");
  else
    skip(p.liquid, mask_->any_wet(), "liquid (no texel at or above the threshold)");
  if (p.liquid) {
    skip(p.liquid_rim, g.tilt_s > 0 || g.tilt_t > 0, "liquid rim normals (tilt = 0)");
    skip(p.liquid_offset, g.d > 0, "liquid film offset (d = 0)");
    skip(p.liquid_reflection, g.cr > 0, "liquid environment reflection (cr = 0)");
  }
  return p;
}

namespace {

// The ids of the assets in FilteredTextures (texture_filter: mipmap).
struct FilteredIds {
  int environment = -1, ground = -1, normal = -1, ice = -1;
};

// A ray's footprint (texture_filter: mipmap): the change of a point or direction from this
// pixel's ray to the rays through the next pixel to the right (dx) and below (dy).
struct Differential {
  Vector3d dx = Vector3d::Zero(), dy = Vector3d::Zero();
};
struct RayDifferential {
  Differential o, d;  ///< of the origin and of the (unit) direction
};

// Where the two neighbouring rays of `rd` meet the plane through p with normal n, relative to p.
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

// The footprint of reflect(V, N) from that of the ray direction dd (= -dV) and of N.
Differential reflected_footprint(const Vector3d& V, const Differential& dd, const Vector3d& N, const Differential& dN) {
  return {reflect_differential(V, -dd.dx, N, dN.dx), reflect_differential(V, -dd.dy, N, dN.dy)};
}

// Everything a frame needs, read-only while the tiles run.
// The first surface along a primary ray (the fog pass needs its distance, point and normal).
struct FirstSurface {
  bool hit = false, ice = false;
  double t = 0;
  Vector3d p = Vector3d::Zero(), n = Vector3d::UnitZ();  ///< n: unit, facing the eye
};

struct FrameContext {
  const RenderScene& scene;
  const ShadingPlan& plan;
  const MeshBvh& bvh;
  const sim::LiquidMask* mask;
  const RgbImage& env;
  const RgbImage& ground_tex;
  const RgbImage& normal_tex;
  const RgbImage& ice_tex;
  double ground_z;
  double eps;
  double ground_far;
  std::vector<Vector3d> to_light;
  std::vector<std::uint8_t> wet_window;        ///< per texel (WetWindow), empty if not usable
  const FilteredTextures* filtered = nullptr;  ///< texture_filter: mipmap
  FilteredIds ids;

  // Environment along d; `dd` its footprint (nullptr: none, the finest level).
  Rgb env_at(const Vector3d& d, const Differential* dd = nullptr) const {
    if (!filtered) return sample_latlong(env, d);
    return dd ? filtered->environment(ids.environment, d, dd->dx, dd->dy)
              : filtered->environment(ids.environment, d, Vector3d::Zero(), Vector3d::Zero());
  }

  // ---- the liquid mask ----
  // Not sample_bilinear: the mask is sim's float grid (not an image), and with `zero_outside`
  // texels beyond the grid read 0 (dry) rather than the border texel, so the puddle ends at the
  // grid's edge. Without it the arithmetic is sample_bilinear's with kClamp.
  double mask_bilinear(const std::vector<float>& v, double tx, double ty, bool zero_outside) const {
    const auto& p = mask->params();
    const double x0 = std::floor(tx), y0 = std::floor(ty);
    const double fx = tx - x0, fy = ty - y0;
    auto texel = [&](int i, int j) -> double {
      if (zero_outside && (i < 0 || j < 0 || i >= p.width || j >= p.height)) return 0.0;
      i = std::clamp(i, 0, p.width - 1);
      j = std::clamp(j, 0, p.height - 1);
      return static_cast<double>(v[static_cast<std::size_t>(j) * p.width + i]);
    };
    const int i = static_cast<int>(x0), j = static_cast<int>(y0);
    return (1 - fy) * ((1 - fx) * texel(i, j) + fx * texel(i + 1, j)) +
           fy * ((1 - fx) * texel(i, j + 1) + fx * texel(i + 1, j + 1));
  }
  // step(p, mask) at texel coordinates (texel centres at integers).
  double wet(double tx, double ty) const {
    const double m = mask_bilinear(mask->values(), tx, ty, true);
    const double p = mask->threshold_texture().empty() ? static_cast<double>(mask->params().threshold)
                                                       : mask_bilinear(mask->threshold_texture(), tx, ty, false);
    return m >= p ? 1.0 : 0.0;
  }

  // A tiled image at (s, t) in periods: bilinear, or filtered (`id`) with the footprint
  // (d(s,t)/dx, d(s,t)/dy; nullptr: none, the finest level).
  Rgb image_at(const RgbImage& img, int id, const Eigen::Vector2d& st, const Eigen::Vector2d* dx,
               const Eigen::Vector2d* dy) const {
    if (!filtered)
      return sample_bilinear_rgb(img, st.x() * img.width() - 0.5, st.y() * img.height() - 0.5, ImageWrap::kRepeat,
                                 ImageWrap::kRepeat);
    return filtered->texture(id, st.x(), st.y(), dx ? *dx : Eigen::Vector2d::Zero(),
                             dy ? *dy : Eigen::Vector2d::Zero());
  }
  // The same for an image projected along world axis `axis` with period `tile` at point x
  // (the normal map and the ice texture); `dx` the footprint of x.
  Rgb projected_image_at(const RgbImage& img, int id, const Vector3d& x, int axis, double tile,
                         const Differential* dx) const {
    auto uv = [&](const Vector3d& q) {
      return Eigen::Vector2d((axis == 0 ? q.y() : q.x()) / tile, (axis == 2 ? q.y() : q.z()) / tile);
    };
    if (!dx) return image_at(img, id, uv(x), nullptr, nullptr);
    const Eigen::Vector2d ddx = uv(dx->dx), ddy = uv(dx->dy);
    return image_at(img, id, uv(x), &ddx, &ddy);
  }

  // tdiff at (s, t) in texture periods; `dst` the footprint in periods (x, y components).
  Rgb ground_tdiff(double s, double t, const Differential* dst) const {
    if (!dst) return image_at(ground_tex, ids.ground, Eigen::Vector2d(s, t), nullptr, nullptr);
    const Eigen::Vector2d dx = dst->dx.head<2>(), dy = dst->dy.head<2>();
    return image_at(ground_tex, ids.ground, Eigen::Vector2d(s, t), &dx, &dy);
  }

  // The ice's tdiff at p: the milky ice, or the projected image.
  Rgb ice_tdiff(const Vector3d& p, const MeshHit& h, const Differential* dp) const {
    if (ice_tex.empty()) return Rgb::Constant(milky_ice(p, scene.ice.texture_scale));
    return projected_image_at(ice_tex, ids.ice, p, dominant_axis(h.ng), scene.ice.texture_tile, dp);
  }

  // Eq. 7.17 (or plain Phong off the puddle) at ground point q seen along direction d;
  // `dq`, `dd`: the footprint of q and of d (nullptr: none).
  Rgb shade_ground(const Vector3d& q, const Vector3d& d, const Differential* dq, const Differential* dd) const {
    const GroundMaterial& g = scene.ground;
    const Vector3d V = -d.normalized();
    double w = 0;
    Vector3d n(0, 0, 1);
    double tx = 0, ty = 0;
    if (plan.liquid) {
      const auto& mp = mask->params();
      tx = (q.x() - mp.origin.x()) / mp.texel_size - 0.5;
      ty = (q.y() - mp.origin.y()) / mp.texel_size - 0.5;
      bool near_grid = tx > -3 && ty > -3 && tx < mp.width + 2 && ty < mp.height + 2;
      if (near_grid && !wet_window.empty() && tx >= 0 && ty >= 0 && tx < mp.width && ty < mp.height) {
        const auto state = wet_window[static_cast<std::size_t>(ty) * mp.width + static_cast<std::size_t>(tx)];
        if (state != kMixed) {  // the five tests agree: w = 0 or 1, the rim normal is flat
          w = state == kWet ? 1.0 : 0.0;
          near_grid = false;
        }
      }
      // Beyond the grid the border reads zero: no liquid and no rim there.
      if (near_grid) w = wet(tx, ty);
      if (near_grid && plan.liquid_rim) {
        n = Vector3d(g.tilt_s * (wet(tx - 1, ty) - wet(tx + 1, ty)), g.tilt_t * (wet(tx, ty - 1) - wet(tx, ty + 1)),
                     1.0)
                .normalized();
      }
    }
    double s = q.x() / g.tile, t = q.y() / g.tile;
    if (plan.liquid_offset && w > 0) {
      s -= g.d * V.x() * w;
      t -= g.d * V.y() * w;
    }
    Rgb tdiff(1, 1, 1);
    if (g.textured) {
      const Differential dst = dq ? Differential{dq->dx / g.tile, dq->dy / g.tile} : Differential{};
      tdiff = ground_tdiff(s, t, dq ? &dst : nullptr);
    }
    const Vector3d ns = g.rs_uses_n_star ? n : Vector3d(0, 0, 1);
    Rgb diffuse = Rgb::Constant(g.ca), spec = Rgb::Zero();
    for (std::size_t k = 0; k < to_light.size(); ++k) {
      const Vector3d& L = to_light[k];
      const Rgb& Izr = scene.lights[k].colour;
      diffuse += Izr * g.cd * std::max(0.0, n.dot(L));
      if (plan.ground_specular) {
        const Vector3d Rs = reflect(L, ns);
        spec += Izr * g.cs * pow_pos(Rs.dot(V), g.n_spec);
      }
    }
    Rgb I = diffuse.cwiseProduct(tdiff) + spec;
    if (w > 0) {
      I = pow_rgb(I, 1.0 + g.a * w);
      if (plan.liquid_reflection) {
        const Differential dR = dd ? reflected_footprint(V, *dd, n, Differential{}) : Differential{};
        I += g.cr * w * env_at(reflect(V, n), dd ? &dR : nullptr);
      }
    }
    return I;
  }

  // Ground or environment along a ray that does not look at the ice (or after it).
  // Rays almost parallel to the ground meet it at the horizon: beyond ground_far they see the
  // environment (this also keeps texel coordinates far inside the range of int).
  Rgb background(const Vector3d& o, const Vector3d& d, const RayDifferential* rd) const {
    if (d.z() < 0 && o.z() > ground_z) {
      const double t = (ground_z - o.z()) / d.z();
      if (t < ground_far) {
        const Vector3d q = o + t * d;
        const Differential dq = rd ? plane_footprint(o, d, *rd, q, Vector3d::UnitZ(), ground_far) : Differential{};
        return shade_ground(q, d, rd ? &dq : nullptr, rd ? &rd->d : nullptr);
      }
    }
    return env_at(d, rd ? &rd->d : nullptr);
  }

  // Scene radiance along a secondary ray (physical model): the ice again gives its
  // environment value (no further recursion), else ground or environment.
  Rgb trace_secondary(const Vector3d& o, const Vector3d& d, const RayDifferential* rd) const {
    MeshHit h;
    const double t_ground = (d.z() < 0 && o.z() > ground_z) ? (ground_z - o.z()) / d.z() : kInf;
    if (bvh.intersect(o, d, eps, t_ground, h)) return env_at(d, rd ? &rd->d : nullptr);
    return background(o, d, rd);
  }

  // The shading normal facing V (normal-mapped if planned); with a footprint `dp` of p also
  // its change dN (of the interpolated normal; the normal map's own slope change is not
  // followed) and the map's filtered lookup.
  Vector3d ice_normal(const Vector3d& p, const MeshHit& h, const Vector3d& V, const Differential* dp,
                      Differential* dN) const {
    Vector3d n = bvh.shading_normal(h);
    if (dp) *dN = {bvh.shading_normal_differential(h, dp->dx), bvh.shading_normal_differential(h, dp->dy)};
    if (plan.normal_map) {
      Vector3d t, b;
      int axis = 2;
      tangent_frame(n, h.ng, t, b, axis);
      const Rgb enc = projected_image_at(normal_tex, ids.normal, p, axis, scene.ice.normal_map_tile, dp);
      const Vector3d nm = 2.0 * (enc - Rgb::Constant(0.5));  // Eq. 6.12
      n = (nm.x() * t + nm.y() * b + nm.z() * n).normalized();
    }
    if (n.dot(V) < 0) {  // face the eye (back faces seen from inside, bent normals)
      n = -n;
      if (dp) *dN = {-dN->dx, -dN->dy};
    }
    return n;
  }

  // `rd`: the footprint at the hit (o = that of p, d = that of the ray direction), or nullptr.
  Rgb shade_ice_monograph(const Vector3d& p, const MeshHit& h, const Vector3d& d, const RayDifferential* rd) const {
    const IceMaterial& m = scene.ice;
    const Vector3d V = -d.normalized();
    Differential dN;
    const Vector3d N = ice_normal(p, h, V, rd ? &rd->o : nullptr, &dN);
    Rgb I = Rgb::Zero();
    if (plan.ice_texture || plan.ice_specular) {
      Rgb diffuse = Rgb::Constant(m.ca), spec = Rgb::Zero();
      for (std::size_t k = 0; k < to_light.size(); ++k) {
        const Vector3d& L = to_light[k];
        const Rgb& Izr = scene.lights[k].colour;
        if (plan.ice_texture) diffuse += Izr * m.cd * std::max(0.0, N.dot(L));
        if (plan.ice_specular) {
          const Vector3d Rs = reflect(L, N);
          const double x = m.specular == SpecularTerm::kRsV ? Rs.dot(V) : Rs.dot(L);
          spec += Izr * m.cs * pow_pos(x, m.n_spec);
        }
      }
      if (plan.ice_texture) I += diffuse.cwiseProduct(ice_tdiff(p, h, rd ? &rd->o : nullptr));
      I += spec;
    }
    if (!plan.fresnel) return I;
    const double cos_i = std::clamp(N.dot(V), 0.0, 1.0);
    const double eta_ice = plan.dispersion ? m.eta_rgb[1] : m.eta;
    const double F = fresnel(m.fresnel, cos_i, 1.0, eta_ice);
    if (plan.ice_reflection) {
      const Differential dR = rd ? reflected_footprint(V, rd->d, N, dN) : Differential{};
      I += m.cr * F * env_at(reflect(V, N), rd ? &dR : nullptr);
    }
    if (plan.ice_transmission) {
      auto seen_through = [&](double eta_rel) -> std::optional<Rgb> {
        const auto T = refract(-V, N, eta_rel);
        if (!T) return std::nullopt;
        if (!rd) return env_at(*T);
        const Differential dT{refract_differential(-V, rd->d.dx, N, dN.dx, eta_rel),
                              refract_differential(-V, rd->d.dy, N, dN.dy, eta_rel)};
        return env_at(*T, &dT);
      };
      if (plan.dispersion) {
        for (int c = 0; c < 3; ++c)
          if (const auto L = seen_through(1.0 / m.eta_rgb[static_cast<std::size_t>(c)]))
            I[c] += m.ct * (1 - F) * (*L)[c];
      } else if (const auto L = seen_through(1.0 / m.eta)) {
        I += m.ct * (1 - F) * *L;
      }
    }
    return I;
  }

  Rgb shade_ice_physical(const Vector3d& p, const MeshHit& h, const Vector3d& d, const RayDifferential* rd) const {
    const IceMaterial& m = scene.ice;
    const Vector3d V = -d.normalized();
    Differential dN;
    const Vector3d N = ice_normal(p, h, V, rd ? &rd->o : nullptr, &dN);
    const double cos_i = std::clamp(N.dot(V), 0.0, 1.0);
    Rgb I = Rgb::Zero();
    const int channels = plan.dispersion ? 3 : 1;
    // Reflection with each channel's own Fresnel weight, so that reflected + transmitted = 1
    // per channel (the white-furnace test checks this bookkeeping). Only the mirrored ray
    // carries a footprint; the paths through the ice look up the finest level.
    const RayDifferential mirror =
        rd ? RayDifferential{rd->o, reflected_footprint(V, rd->d, N, dN)} : RayDifferential{};
    const Rgb from_mirror = trace_secondary(p + eps * N, reflect(V, N), rd ? &mirror : nullptr);
    if (!plan.dispersion) I += fresnel(m.fresnel, cos_i, 1.0, m.eta) * from_mirror;
    for (int c = 0; c < channels; ++c) {
      const double eta = plan.dispersion ? m.eta_rgb[static_cast<std::size_t>(c)] : m.eta;
      const double F = fresnel(m.fresnel, cos_i, 1.0, eta);
      if (plan.dispersion) I[c] += F * from_mirror[c];
      const auto T = refract(-V, N, 1.0 / eta);
      if (!T) continue;
      Vector3d dir = *T, o = p - eps * N;
      Rgb weight = Rgb::Constant(1 - F);
      for (int bounce = 0; bounce <= m.max_internal_bounces; ++bounce) {
        MeshHit e;
        if (!bvh.intersect(o, dir, eps, kInf, e)) {  // leaked through a crack: see the environment
          const Rgb L = env_at(dir);
          if (plan.dispersion)
            I[c] += weight[c] * L[c];
          else
            I += weight.cwiseProduct(L);
          break;
        }
        for (int k = 0; k < 3; ++k) weight[k] *= std::exp(-m.absorption[static_cast<std::size_t>(k)] * e.t);
        const Vector3d q = o + e.t * dir;
        Vector3d n_out = bvh.shading_normal(e);
        if (n_out.dot(dir) < 0) n_out = -n_out;  // the normal on the far side of the interface
        const double cos_x = std::clamp(dir.dot(n_out), 0.0, 1.0);
        const double Fx = fresnel(m.fresnel, cos_x, eta, 1.0);
        const Vector3d reflected = dir - 2.0 * dir.dot(n_out) * n_out;
        if (const auto out = refract(dir, -n_out, eta)) {
          const Rgb L = trace_secondary(q + eps * n_out, *out, nullptr);
          if (plan.dispersion)
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

  // Radiance along the primary ray o + t·d (d unit); `rd` its footprint or nullptr.
  // `first` (if given) receives the first surface along the ray: for the fog pass.
  Rgb shade(const Vector3d& o, const Vector3d& d, const RayDifferential* rd, FirstSurface* first = nullptr) const {
    MeshHit h;
    const double t_ground = (d.z() < 0 && o.z() > ground_z) ? (ground_z - o.z()) / d.z() : kInf;
    const bool ice = bvh.intersect(o, d, 0.0, t_ground, h);
    if (first) {
      *first = FirstSurface{};
      if (ice) {
        const Vector3d n = bvh.shading_normal(h);
        *first = FirstSurface{true, true, h.t, o + h.t * d, n.dot(d) > 0 ? Vector3d(-n) : n};
      } else if (t_ground < ground_far) {
        *first = FirstSurface{true, false, t_ground, o + t_ground * d, Vector3d::UnitZ()};
      }
    }
    if (ice) {
      const Vector3d p = o + h.t * d;
      const RayDifferential at_hit =
          rd ? RayDifferential{plane_footprint(o, d, *rd, p, h.ng, ground_far), rd->d} : RayDifferential{};
      const RayDifferential* hit_rd = rd ? &at_hit : nullptr;
      return scene.ice.model == IceModel::kMonograph ? shade_ice_monograph(p, h, d, hit_rd)
                                                     : shade_ice_physical(p, h, d, hit_rd);
    }
    return background(o, d, rd);
  }
};

}  // namespace

RgbImage IceRenderer::render() {
  const auto t0 = std::chrono::steady_clock::now();
  if (!camera_) {
    if (!scene_.camera)
      camera_ = auto_camera(Vector3d(-1, -1, 0), Vector3d(1, 1, 1), scene_.width, scene_.height);
    else
      camera_ = scene_.camera;
  }
  const ShadingPlan p = plan();
  std::string log = fmt::format("{}", fmt::join(p.skipped, "; "));
  if (log != last_plan_log_) {
    spdlog::info("render: skipped: {}", log.empty() ? "nothing" : log);
    last_plan_log_ = log;
  }
  const double ground_z = scene_.ground.z.value_or(0.0);
  FrameContext ctx{scene_,
                   p,
                   bvh_,
                   mask_,
                   env_,
                   ground_tex_,
                   normal_tex_,
                   ice_tex_,
                   ground_z,
                   1e-4 * object_size_,
                   1e6 * object_size_,
                   {},
                   {},
                   filtered_.get(),
                   {env_id_, ground_id_, normal_id_, ice_id_}};
  for (const auto& l : scene_.lights) ctx.to_light.push_back(l.to_light.normalized());
  if (p.liquid && mask_->threshold_texture().empty() && mask_->params().threshold > 0)
    ctx.wet_window = wet_windows(*mask_);
  const Camera& cam = *camera_;
  const int w = camera_width(cam), h = camera_height(cam);
  const double z_top = std::max(bvh_.upper().z(), ground_z) + object_size_;
  const RayGenerator rays(cam, z_top);
  RgbImage img = rgb_image(w, h);
  const fog::FogMaterial fog_ice = fog::FogShader::material(scene_.ice.cd, scene_.ice.cs, scene_.ice.n_spec);
  const fog::FogMaterial fog_ground =
      fog::FogShader::material(scene_.ground.cd, scene_.ground.cs, scene_.ground.n_spec);
  tbb::parallel_for(tbb::blocked_range2d<int>(0, h, 16, 0, w, 16), [&](const tbb::blocked_range2d<int>& r) {
    for (int j = r.rows().begin(); j < r.rows().end(); ++j)
      for (int i = r.cols().begin(); i < r.cols().end(); ++i) {
        const CameraRay ray = rays.generate_ray(i, j);
        if (!ray.ok) {
          set_rgb(img, i, j, Rgb::Zero());
        } else if (fog_) {  // the fog pass on the shaded pixel (bilinear lookups)
          FirstSurface first;
          const Rgb c = ctx.shade(ray.origin, ray.direction, nullptr, &first);
          const fog::SurfaceHit hit{first.p, first.n, first.ice ? &fog_ice : &fog_ground};
          set_rgb(img, i, j, fog_->apply(c, ray.origin, ray.direction, first.t, first.hit ? &hit : nullptr));
        } else if (!ctx.filtered) {
          set_rgb(img, i, j, ctx.shade(ray.origin, ray.direction, nullptr));
        } else {  // the footprint: the rays through the next pixel to the right and below
          const CameraRay rx = rays.generate_ray(i + 1, j);
          const CameraRay ry = rays.generate_ray(i, j + 1);
          const RayDifferential rd{{rx.origin - ray.origin, ry.origin - ray.origin},
                                   {rx.direction - ray.direction, ry.direction - ray.direction}};
          // A neighbour whose undistortion did not converge gives no footprint (finest level).
          set_rgb(img, i, j, ctx.shade(ray.origin, ray.direction, rx.ok && ry.ok ? &rd : nullptr));
        }
      }
  });
  stats_.trace_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return img;
}

}  // namespace meltlab::render
