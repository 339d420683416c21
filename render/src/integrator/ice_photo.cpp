// Photo-like rendering of voxel ice on a textured ground (see integrator/ice_photo.h).

#include <meltlab/render/integrator/ice_photo.h>
#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/core/image.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::render {

using meltlab::Grid3;
using sim::physics::IceFraction;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- hashing (counter-based, no shared state) ------------------------------------------

inline std::uint64_t hash3(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return splitmix64(splitmix64(splitmix64(a) ^ b) ^ c);
}

// ---- ray / box ------------------------------------------------------------------------------

struct Box {
  Vec3d lo, hi;
  bool empty = true;
};

/// [t0, t1] of the ray o + t d inside the box (slab method, per-axis swap; vlr.slab.swap);
/// false on a miss. Axes with d = 0 require o inside the slab.
bool slab(const Box& b, const Vec3d& o, const Vec3d& d, double& t0, double& t1) {
  if (b.empty) return false;
  t0 = -kInf;
  t1 = kInf;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return false;
      continue;
    }
    double tn = (b.lo[a] - o[a]) / d[a], tf = (b.hi[a] - o[a]) / d[a];
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
  }
  return t0 <= t1;
}

/// The box where the trilinear interpolant of `g` can reach `threshold` (> 0: values ≥ it;
/// a convex combination reaches it only within one cell of a cell that does), clipped to the grid.
template <class T>
Box support_box(const Grid3<T>& g, double threshold, bool strictly_positive) {
  int lo[3] = {g.nx, g.ny, g.nz}, hi[3] = {-1, -1, -1};
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const double v = g.at(i, j, k);
        if (strictly_positive ? v > 0.0 : v >= threshold) {
          lo[0] = std::min(lo[0], i), lo[1] = std::min(lo[1], j), lo[2] = std::min(lo[2], k);
          hi[0] = std::max(hi[0], i), hi[1] = std::max(hi[1], j), hi[2] = std::max(hi[2], k);
        }
      }
  Box b;
  if (hi[0] < 0) return b;
  const int n[3] = {g.nx, g.ny, g.nz};
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = g.origin_m[a] + g.h_m * std::max(0.0, lo[a] - 0.5);
    b.hi[a] = g.origin_m[a] + g.h_m * std::min(double(n[a]), hi[a] + 1.5);
  }
  b.empty = false;
  return b;
}

// ---- ground texture ----------------------------------------------------------------------------

/// The lattice values of the last cell visited per octave: neighbouring pixels mostly share
/// them (the coarse octaves span many pixels), and recomputing a lattice value costs 3 hashes.
struct TextureCache {
  std::int64_t ix[4] = {0, 0, 0, 0}, iy[4] = {0, 0, 0, 0};
  double lat[4][4] = {};
  bool valid[4] = {false, false, false, false};
};

double ground_texture_impl(double x_m, double y_m, double scale_m, std::uint64_t seed, TextureCache& cache) {
  if (!(scale_m > 0.0)) return 0.0;
  // fBm of value noise: 4 octaves, lacunarity 2, gain 0.5, quintic fade; in [-1, 1].
  double sum = 0, norm = 0, amp = 1, freq = 1.0 / scale_m;
  for (int oct = 0; oct < 4; ++oct) {
    const double x = x_m * freq, y = y_m * freq;
    const double fx = std::floor(x), fy = std::floor(y);
    const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
    auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
    const double tx = fade(x - fx), ty = fade(y - fy);
    auto lat = [&](std::int64_t a, std::int64_t b) {
      return 2.0 * unit_from_bits(hash3(seed * 8 + std::uint64_t(oct), std::uint64_t(a), std::uint64_t(b))) - 1.0;
    };
    double* l = cache.lat[oct];
    if (cache.valid[oct] && cache.iy[oct] == iy && cache.ix[oct] + 1 == ix) {  // the next cell along x
      l[0] = l[1];
      l[2] = l[3];
      l[1] = lat(ix + 1, iy);
      l[3] = lat(ix + 1, iy + 1);
      cache.ix[oct] = ix;
    } else if (!cache.valid[oct] || cache.ix[oct] != ix || cache.iy[oct] != iy) {
      l[0] = lat(ix, iy);
      l[1] = lat(ix + 1, iy);
      l[2] = lat(ix, iy + 1);
      l[3] = lat(ix + 1, iy + 1);
      cache.ix[oct] = ix;
      cache.iy[oct] = iy;
      cache.valid[oct] = true;
    }
    const double v = (l[0] * (1 - tx) + l[1] * tx) * (1 - ty) + (l[2] * (1 - tx) + l[3] * tx) * ty;
    sum += amp * v;
    norm += amp;
    amp *= 0.5;
    freq *= 2.0;
  }
  return sum / norm;
}

// ---- the scene -------------------------------------------------------------------------------

/// The photo's scene: the voxel ice is traced by the one volume integrator (VolumeTracer:
/// HGAttenuated with κ in the BRDF, the exponential step at midpoints of equal steps <= step_m,
/// the lamp as a directional light, the sky as its ambient term, shadows from its shadow cache
/// or marched); the ground plane behind it is shaded here.
struct Scene {
  const IcePhotoOptions& opt;
  Volume volume;
  std::unique_ptr<VolumeTracer> tracer;  // none when the ice cannot attenuate (σ = 0)
  Vec3d to_lamp;

  static VolumeRenderSettings settings_for(const IceFraction& g, const IcePhotoOptions& o, const Vec3d& to_lamp) {
    VolumeRenderSettings s;
    s.model = o.shadow == IcePhotoOptions::Shadow::kNone ? OpticalModel::kHG : OpticalModel::kHGAttenuated;
    s.shadow = o.shadow == IcePhotoOptions::Shadow::kMarch ? ShadowMethod::kMarch : ShadowMethod::kCache;
    s.shadow_cache_build = ShadowCacheBuild::kSweep;
    s.step_rule = StepRule::kFitSegment;
    s.step = o.step_m > 0 ? o.step_m : 0.5 * g.h_m;
    s.shadow_step = s.step;
    s.first_offset = FirstOffset::kHalf;
    s.quadrature = Quadrature::kExponential;
    s.kappa = o.extinction_per_m;
    s.gamma = 1.0;
    s.kappa_in_brdf = true;  // S = a σ (L p T_lamp + sky), [3.8]
    s.albedo = o.albedo;
    s.hg_c = o.hg_g;
    s.emission = Rgb::Zero();
    const Rgb tint(o.ice_tint_rgb[0], o.ice_tint_rgb[1], o.ice_tint_rgb[2]);
    VolumeLight lamp;
    lamp.type = LightType::kDirectional;
    lamp.to_light = to_lamp;
    lamp.intensity = o.lamp_irradiance * tint;
    s.lights = {lamp};
    s.ambient = o.sky_radiance * tint;
    s.ert_transmittance = o.min_transmittance;
    s.skip_empty = o.skip_empty_space;
    s.parallel = o.parallel;
    return s;
  }

  Scene(const IceFraction& g, const IcePhotoOptions& o) : opt(o) {
    if (g.empty() || !(g.h_m > 0)) throw InputError("render_ice_photo: empty ice grid or non-positive cell size");
    if (!(o.to_lamp.z() > 0.0) || !o.to_lamp.allFinite())
      throw InputError("render_ice_photo: to_lamp must point upwards (z > 0)");
    if (!(o.extinction_per_m >= 0.0) || !(o.hg_g > -1.0 && o.hg_g < 1.0) || o.supersample < 1 || !(o.step_m >= 0.0))
      throw InputError("render_ice_photo: bad options (extinction >= 0, -1 < hg_g < 1, supersample >= 1, step >= 0)");
    to_lamp = o.to_lamp.normalized();
    volume = Volume::view_of(g);
    if (o.extinction_per_m > 0) tracer = std::make_unique<VolumeTracer>(volume, settings_for(g, o, to_lamp));
  }

  /// Linear RGB radiance along the ray o + t d (d unit).
  std::array<double, 3> trace(const Vec3d& o, const Vec3d& d, std::uint64_t pixel, TextureCache& texture) const {
    std::array<double, 3> rad{0, 0, 0};
    double T = 1.0;
    double t_ground = kInf;
    if (d.z() < 0.0) t_ground = (opt.ground_z_m - o.z()) / d.z();
    if (t_ground < 0.0) t_ground = kInf;  // camera below the ground: no ground in view
    if (tracer) {
      const VolumeTracer::Result r = tracer->trace(o, d, t_ground, pixel);
      for (std::size_t c = 0; c < 3; ++c) rad[c] = r.radiance[int(c)];
      T = r.transmittance;
      if (T < opt.min_transmittance) return rad;  // opaque: nothing behind shows
    }
    if (t_ground == kInf) {  // the sky
      for (auto& r : rad) r += T * opt.sky_radiance;
      return rad;
    }
    const Vec3d g = o + t_ground * d;
    const double rho =
        opt.ground_albedo *
        std::max(0.0, 1.0 + opt.ground_texture_contrast * ground_texture_impl(g.x(), g.y(), opt.ground_texture_scale_m,
                                                                              opt.ground_seed, texture));
    double Tl = 1.0, Tz = 1.0;
    if (opt.shadow != IcePhotoOptions::Shadow::kNone && tracer) {
      Tl = tracer->transmittance(g, to_lamp);
      Tz = tracer->transmittance(g, Vec3d(0, 0, 1));
    }
    const double e = rho * (opt.lamp_irradiance / std::numbers::pi * to_lamp.z() * Tl + opt.sky_radiance * Tz);
    for (std::size_t c = 0; c < 3; ++c) rad[c] += T * e * opt.ground_tint_rgb[c];
    return rad;
  }
};

template <class RowFn>
void for_rows(int rows, bool parallel, const RowFn& fn) {
  if (parallel) {
    tbb::parallel_for(tbb::blocked_range<int>(0, rows, 4), [&](const tbb::blocked_range<int>& r) {
      for (int v = r.begin(); v < r.end(); ++v) fn(v);
    });
  } else {
    for (int v = 0; v < rows; ++v) fn(v);
  }
}

double top_of_scene(const IceFraction& ice, double ground_z) { return std::max(ice.max_m().z(), ground_z) + 1.0; }

}  // namespace

double ground_texture(double x_m, double y_m, double scale_m, std::uint64_t seed) {
  TextureCache cache;
  return ground_texture_impl(x_m, y_m, scale_m, seed, cache);
}

cv::Mat render_ice_radiance(const IceFraction& ice_in, const Camera& camera, const IcePhotoOptions& options,
                            const cv::Mat& only) {
  if (!(options.interface_width >= 0.0) || !std::isfinite(options.interface_width))
    throw InputError(
        fmt::format("ice photo: interface_width must be a finite number >= 0 (got {})", options.interface_width));
  IceFraction sharpened;
  if (options.interface_width > 0) {
    sharpened = ice_in;
    const float w = static_cast<float>(options.interface_width);
    for (float& f : sharpened.value) f = std::clamp((f - 0.5F) / w + 0.5F, 0.0F, 1.0F);
  }
  const IceFraction& ice = options.interface_width > 0 ? sharpened : ice_in;
  const Scene scene(ice, options);
  const int W = camera_width(camera), H = camera_height(camera);
  const RayGenerator gen(camera, top_of_scene(ice, options.ground_z_m));
  const int k = options.supersample;
  if (!only.empty() && (only.type() != CV_8UC1 || only.cols != W || only.rows != H))
    throw InputError("render_ice_radiance: the pixel selection must be CV_8UC1 of the image size");
  cv::Mat out(H, W, CV_32FC3, cv::Scalar::all(0));
  for_rows(H, options.parallel, [&](int v) {
    auto* row = out.ptr<cv::Vec3f>(v);
    const std::uint8_t* sel = only.empty() ? nullptr : only.ptr<std::uint8_t>(v);
    TextureCache texture;
    for (int u = 0; u < W; ++u) {
      if (sel && !sel[u]) continue;
      std::array<double, 3> acc{0, 0, 0};
      for (int t = 0; t < k; ++t)
        for (int s = 0; s < k; ++s) {
          const CameraRay ray = gen.generate_ray(u - 0.5 + (s + 0.5) / k, v - 0.5 + (t + 0.5) / k);
          if (!ray.ok) continue;
          const auto r =
              scene.trace(ray.origin, ray.direction, std::uint64_t(v) * std::uint64_t(W) + std::uint64_t(u), texture);
          for (std::size_t c = 0; c < 3; ++c) acc[c] += r[c];
        }
      const double inv = 1.0 / (k * k);
      row[u] = cv::Vec3f(float(acc[2] * inv), float(acc[1] * inv), float(acc[0] * inv));  // BGR
    }
  });
  return out;
}

cv::Mat develop_photo(const cv::Mat& radiance, const IcePhotoOptions& options) {
  if (radiance.type() != CV_32FC3) throw InputError("develop_photo: radiance must be CV_32FC3");
  cv::Mat lin = radiance * options.exposure;
  if (options.lens_blur_sigma_px > 0) {
    cv::GaussianBlur(lin, lin, cv::Size(0, 0), options.lens_blur_sigma_px, options.lens_blur_sigma_px,
                     cv::BORDER_REFLECT);
  }
  cv::Mat out(lin.size(), CV_8UC3);
  const double inv_gamma = options.gamma > 0 ? 1.0 / options.gamma : 1.0;
  for_rows(lin.rows, options.parallel, [&](int v) {
    const auto* in = lin.ptr<cv::Vec3f>(v);
    auto* o = out.ptr<cv::Vec3b>(v);
    for (int u = 0; u < lin.cols; ++u)
      for (int c = 0; c < 3; ++c) {
        double x = 255.0 * std::pow(std::clamp(double(in[u][c]), 0.0, 1.0), inv_gamma);
        if (options.noise_sigma > 0) {
          const std::uint64_t id =
              (std::uint64_t(v) * std::uint64_t(lin.cols) + std::uint64_t(u)) * 3 + std::uint64_t(c);
          const std::uint64_t h = hash3(options.seed, id, 0x6e6f697365ull);
          const double u1 = unit_from_bits(h), u2 = unit_from_bits(splitmix64(h));
          x += options.noise_sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
        }
        o[u][c] = static_cast<std::uint8_t>(std::clamp(std::lround(x), 0L, 255L));
      }
  });
  return out;
}

cv::Mat render_ice_photo(const IceFraction& ice, const Camera& camera, const IcePhotoOptions& options) {
  return develop_photo(render_ice_radiance(ice, camera, options), options);
}

cv::Mat ice_true_mask(const IceFraction& ice, const Camera& camera, double threshold, double ground_z_m) {
  if (ice.empty() || !(ice.h_m > 0)) throw InputError("ice_true_mask: empty ice grid or non-positive cell size");
  const int W = camera_width(camera), H = camera_height(camera);
  cv::Mat mask(H, W, CV_8UC1, cv::Scalar(0));
  const Box box = support_box(ice, threshold, threshold <= 0.0);
  if (box.empty) return mask;
  const RayGenerator gen(camera, top_of_scene(ice, ground_z_m));
  const double step = ice.h_m / 8.0;
  for_rows(H, true, [&](int v) {
    auto* row = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < W; ++u) {
      const CameraRay ray = gen.generate_ray(u, v);
      if (!ray.ok) continue;
      const Vec3d& o = ray.origin;
      const Vec3d& d = ray.direction;
      double t0 = 0, t1 = 0;
      if (!slab(box, o, d, t0, t1)) continue;
      t0 = std::max(t0, 0.0);
      if (d.z() < 0.0) {
        const double tg = (ground_z_m - o.z()) / d.z();
        if (tg >= 0.0) t1 = std::min(t1, tg);
      }
      if (!(t1 >= t0)) continue;
      const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
      const double dt = (t1 - t0) / n;
      for (int i = 0; i <= n; ++i)
        if (ice.sample(o + (t0 + i * dt) * d) >= threshold) {
          row[u] = 255;
          break;
        }
    }
  });
  return mask;
}

void write_jpeg(const std::filesystem::path& file, const cv::Mat& image, int quality) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    throw InputError(fmt::format("{}: write_jpeg needs a non-empty 8-bit gray or BGR image", file.string()));
  if (quality < 1 || quality > 100)
    throw InputError(fmt::format("{}: JPEG quality must be in [1, 100] (got {})", file.string(), quality));
  // OpenCV's BGR to the image type's RGB.
  Image8 pixels(image.cols, image.rows, image.channels());
  for (int y = 0; y < image.rows; ++y) {
    const std::uint8_t* in = image.ptr<std::uint8_t>(y);
    for (int x = 0; x < image.cols; ++x)
      for (int c = 0; c < image.channels(); ++c)
        pixels.at(x, y, c) = in[x * image.channels() + (image.channels() == 3 ? 2 - c : c)];
  }
  write_image(file, pixels, quality);
}

}  // namespace meltlab::render
