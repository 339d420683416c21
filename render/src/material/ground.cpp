// The ground and the liquid on it, Eq. 2.13 and 7.17 (material/ground.h).

#include <meltlab/render/material/ground.h>
#include <meltlab/render/material/optics.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meltlab::render {

using Eigen::Vector3d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

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

}  // namespace

GroundPlan plan_ground(const GroundMaterial& g, bool lit, const sim::LiquidMask* mask,
                       std::vector<std::string>& skipped) {
  GroundPlan p;
  auto skip = [&](bool& flag, bool keep, const std::string& why) {
    flag = keep;
    if (!keep) skipped.push_back(why);
  };
  skip(p.ground_specular, g.cs > 0 && lit, "ground specular (cs = 0 or no light)");
  const bool visible = g.a > 0 || g.cr > 0 || g.tilt_s > 0 || g.tilt_t > 0 || g.d > 0;
  if (!g.liquid)
    skip(p.liquid, false, "liquid (ground.liquid off)");
  else if (!mask)
    skip(p.liquid, false, "liquid (no mask: sublimation or no liquid stage)");
  else if (!visible)
    skip(p.liquid, false, "liquid (a = cr = tilt = d = 0)");
  else
    skip(p.liquid, mask->any_wet(), "liquid (no texel at or above the threshold)");
  if (p.liquid) {
    skip(p.liquid_rim, g.tilt_s > 0 || g.tilt_t > 0, "liquid rim normals (tilt = 0)");
    skip(p.liquid_offset, g.d > 0, "liquid film offset (d = 0)");
    skip(p.liquid_reflection, g.cr > 0, "liquid environment reflection (cr = 0)");
  }
  return p;
}

// ---- the liquid ----

LiquidFilm::LiquidFilm(const sim::LiquidMask& mask, double tilt_s, double tilt_t, bool rim)
    : mask_(mask), tilt_s_(tilt_s), tilt_t_(tilt_t), rim_(rim) {
  if (mask_.threshold_texture().empty() && mask_.params().threshold > 0) wet_window_ = wet_windows(mask_);
}

// Not sample_bilinear: the mask is sim's float grid (not an image), and with `zero_outside`
// texels beyond the grid read 0 (dry) rather than the border texel, so the puddle ends at the
// grid's edge. Without it the arithmetic is sample_bilinear's with kClamp.
double LiquidFilm::mask_bilinear(const std::vector<float>& v, double tx, double ty, bool zero_outside) const {
  const auto& p = mask_.params();
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

double LiquidFilm::wet(double tx, double ty) const {
  const double m = mask_bilinear(mask_.values(), tx, ty, true);
  const double p = mask_.threshold_texture().empty() ? static_cast<double>(mask_.params().threshold)
                                                     : mask_bilinear(mask_.threshold_texture(), tx, ty, false);
  return m >= p ? 1.0 : 0.0;
}

LiquidFilm::At LiquidFilm::at(const Vector3d& q) const {
  At out;
  const auto& mp = mask_.params();
  const double tx = (q.x() - mp.origin.x()) / mp.texel_size - 0.5;
  const double ty = (q.y() - mp.origin.y()) / mp.texel_size - 0.5;
  bool near_grid = tx > -3 && ty > -3 && tx < mp.width + 2 && ty < mp.height + 2;
  if (near_grid && !wet_window_.empty() && tx >= 0 && ty >= 0 && tx < mp.width && ty < mp.height) {
    const auto state = wet_window_[static_cast<std::size_t>(ty) * mp.width + static_cast<std::size_t>(tx)];
    if (state != kMixed) {  // the five tests agree: w = 0 or 1, the rim normal is flat
      out.w = state == kWet ? 1.0 : 0.0;
      near_grid = false;
    }
  }
  // Beyond the grid the border reads zero: no liquid and no rim there.
  if (near_grid) out.w = wet(tx, ty);
  if (near_grid && rim_) {
    out.n = Vector3d(tilt_s_ * (wet(tx - 1, ty) - wet(tx + 1, ty)), tilt_t_ * (wet(tx, ty - 1) - wet(tx, ty + 1)), 1.0)
                .normalized();
  }
  return out;
}

// ---- the ground ----

WetGround::WetGround(const GroundMaterial& ground, const GroundPlan& plan, const std::vector<Light>& lights,
                     const ImageTexture& tdiff, const EnvironmentTexture& environment, const sim::LiquidMask* mask)
    : material_(ground), plan_(plan), lights_(lights), tdiff_(tdiff), environment_(environment) {
  if (plan_.liquid && mask) liquid_.emplace(*mask, ground.tilt_s, ground.tilt_t, plan_.liquid_rim);
}

Rgb WetGround::texture_at(const Vector3d& q, const Vector3d& V, double w, const Differential* dq) const {
  const GroundMaterial& g = material_;
  if (!g.textured) return Rgb(1, 1, 1);
  // t*diff: the texture shifted by the film (Eq. 7.5).
  double s = q.x() / g.tile, t = q.y() / g.tile;
  if (plan_.liquid_offset && w > 0) {
    s -= g.d * V.x() * w;
    t -= g.d * V.y() * w;
  }
  // The footprint in periods: that of q over the tile (x, y components).
  const Differential2 dst =
      dq ? Differential2{(dq->dx / g.tile).head<2>(), (dq->dy / g.tile).head<2>()} : Differential2{};
  return tdiff_.lookup(Eigen::Vector2d(s, t), dq ? &dst : nullptr);
}

WetGround::FogSurface WetGround::fog_surface(const Vector3d& q, const Vector3d& d, const Differential* dq) const {
  const LiquidFilm::At wet = liquid_ ? liquid_->at(q) : LiquidFilm::At{};
  return FogSurface{texture_at(q, -d.normalized(), wet.w, dq), wet.n};
}

Rgb WetGround::shade(const Vector3d& q, const Vector3d& d, const Differential* dq, const Differential* dd) const {
  const GroundMaterial& g = material_;
  const Vector3d V = -d.normalized();
  const LiquidFilm::At wet = liquid_ ? liquid_->at(q) : LiquidFilm::At{};
  const double w = wet.w;
  const Vector3d& n = wet.n;
  const Rgb tdiff = texture_at(q, V, w, dq);
  // Eq. 7.17: ((ca + Σ Izr·cd·max(0, N*·L))·t*diff + Σ Izr·cs·max(0, Rs·V)^n)^(1 + a·w) + cr·tenv(R*e)·w
  // (plain Phong, Eq. 2.13, where w = 0).
  const Vector3d ns = g.rs_uses_n_star ? n : Vector3d(0, 0, 1);
  Rgb diffuse = Rgb::Constant(g.ca), spec = Rgb::Zero();
  for (const Light& light : lights_) {
    const Vector3d& L = light.to_light;
    const Rgb& Izr = light.colour;
    diffuse += Izr * g.cd * std::max(0.0, n.dot(L));
    if (plan_.ground_specular) {
      const Vector3d Rs = reflect(L, ns);
      spec += Izr * g.cs * pow_pos(Rs.dot(V), g.n_spec);
    }
  }
  Rgb I = diffuse.cwiseProduct(tdiff) + spec;
  if (w > 0) {
    I = pow_rgb(I, 1.0 + g.a * w);
    if (plan_.liquid_reflection) {
      const Differential dR = dd ? reflected_footprint(V, *dd, n, Differential{}) : Differential{};
      I += g.cr * w * environment_.lookup(reflect(V, n), dd ? &dR : nullptr);
    }
  }
  return I;
}

}  // namespace meltlab::render
