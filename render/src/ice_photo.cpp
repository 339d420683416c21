// Photo-like rendering of voxel ice on a textured ground (see ice_photo.h).

#include <meltlab/render/ice_photo.h>
#include <meltlab/sim/atomic_file.h>
#include <meltlab/sim/error.h>

#include <OpenImageIO/imageio.h>
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

using sim::physics::Grid3;
using sim::physics::IceFraction;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- hashing (counter-based, no shared state) ------------------------------------------

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
inline std::uint64_t hash3(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return splitmix64(splitmix64(splitmix64(a) ^ b) ^ c);
}
inline double to_unit(std::uint64_t h) {  // (0, 1)
  return (static_cast<double>(h >> 11) + 0.5) * (1.0 / 9007199254740992.0);
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

// ---- camera rays -----------------------------------------------------------------------------

// Inverse of OpenCV's distortion (Newton), as in silhouette.cpp.
bool undistort_normalized(const std::array<double, 5>& d, double xd, double yd, double& x_out, double& y_out) {
  const double k1 = d[0], k2 = d[1], p1 = d[2], p2 = d[3], k3 = d[4];
  double x = xd, y = yd;
  for (int it = 0; it < 50; ++it) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);
    const double fx = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd;
    const double fy = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd;
    const double j11 = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
    const double j12 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    const double j22 = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
    const double det = j11 * j22 - j12 * j12;
    if (!(det > 0.0) || !(radial > 0.0)) return false;
    if (std::abs(fx) + std::abs(fy) < 1e-13) {
      x_out = x;
      y_out = y;
      return true;
    }
    x -= (j22 * fx - j12 * fy) / det;
    y -= (j11 * fy - j12 * fx) / det;
    if (!std::isfinite(x) || !std::isfinite(y)) return false;
  }
  return false;
}

struct RayGen {
  const Camera& camera;
  double ortho_z = 0;  // orthographic rays start at this height
  Eigen::Matrix3d world_from_camera_R = Eigen::Matrix3d::Identity();
  Vec3d eye = Vec3d::Zero();

  RayGen(const Camera& c, double top_z) : camera(c), ortho_z(top_z) {
    if (const auto* p = std::get_if<Pinhole>(&c)) {
      const Eigen::Isometry3d inv = p->camera_from_world.inverse();
      world_from_camera_R = inv.linear();
      eye = inv.translation();
    }
  }
  /// Ray through image point (u, v); false if it does not exist (undistortion diverges).
  bool ray(double u, double v, Vec3d& o, Vec3d& d) const {
    if (const auto* q = std::get_if<OrthographicTopDown>(&camera)) {
      o = Vec3d(q->centre.x() + (u - 0.5 * (q->width - 1)) / q->pixels_per_unit,
                q->centre.y() - (v - 0.5 * (q->height - 1)) / q->pixels_per_unit, ortho_z);
      d = Vec3d(0, 0, -1);
      return true;
    }
    const auto& p = std::get<Pinhole>(camera);
    double x = (u - p.cx) / p.fx, y = (v - p.cy) / p.fy;
    if (p.distorted() && !undistort_normalized(p.distortion, x, y, x, y)) return false;
    o = eye;
    d = (world_from_camera_R * Vec3d(x, y, 1.0)).normalized();
    return true;
  }
};

// ---- the scene -------------------------------------------------------------------------------

struct Scene {
  const IceFraction& ice;
  const IcePhotoOptions& opt;
  Vec3d to_lamp;
  double step = 0;
  Box box;                       // where f > 0 can be sampled
  Grid3<float> lamp_T;           // Shadow::kGrid: transmittance towards the lamp at cell centres
  std::array<double, 3> a_rgb{}; // albedo × tint
  double phase = 0;              // (per ray; see trace)

  Scene(const IceFraction& g, const IcePhotoOptions& o) : ice(g), opt(o) {
    if (g.empty() || !(g.h_m > 0)) throw InputError("render_ice_photo: empty ice grid or non-positive cell size");
    if (!(o.to_lamp.z() > 0.0) || !o.to_lamp.allFinite())
      throw InputError("render_ice_photo: to_lamp must point upwards (z > 0)");
    if (!(o.extinction_per_m >= 0.0) || !(o.hg_g > -1.0 && o.hg_g < 1.0) || o.supersample < 1 || !(o.step_m >= 0.0))
      throw InputError("render_ice_photo: bad options (extinction >= 0, -1 < hg_g < 1, supersample >= 1, step >= 0)");
    to_lamp = o.to_lamp.normalized();
    step = o.step_m > 0 ? o.step_m : 0.5 * g.h_m;
    box = support_box(g, 0.0, true);
    for (int c = 0; c < 3; ++c) a_rgb[std::size_t(c)] = o.albedo * o.ice_tint_rgb[std::size_t(c)];
    if (o.shadow == IcePhotoOptions::Shadow::kGrid && !box.empty && o.extinction_per_m > 0) build_lamp_grid();
  }

  /// Transmittance from x along unit direction dir to the exit of the ice box (midpoint rule
  /// with equal steps ≤ step: exact for homogeneous media).
  double march_T(const Vec3d& x, const Vec3d& dir) const {
    double t0 = 0, t1 = 0;
    if (!slab(box, x, dir, t0, t1)) return 1.0;
    t0 = std::max(t0, 0.0);
    if (!(t1 > t0)) return 1.0;
    const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
    const double dt = (t1 - t0) / n;
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += ice.sample(x + (t0 + (i + 0.5) * dt) * dir);
    return std::exp(-opt.extinction_per_m * sum * dt);
  }

  void build_lamp_grid() {
    lamp_T = Grid3<float>(ice.nx, ice.ny, ice.nz, ice.h_m, ice.origin_m, 1.0f);
    const double h = ice.h_m;
    // Cells entirely above the ice box see the lamp unobstructed (T = 1): the lamp is above.
    const int k_top = std::min(ice.nz - 1, int(std::ceil((box.hi.z() - ice.origin_m.z()) / h - 0.5)));
    const double len = h / to_lamp.z();  // from one layer's centre plane to the next one's
    const Vec3d off = to_lamp * len;
    const Vec3d lo = ice.min_m(), hi = ice.max_m();
    for (int k = k_top; k >= 0; --k) {
      auto layer = [&](int j0, int j1) {
        for (int j = j0; j < j1; ++j)
          for (int i = 0; i < ice.nx; ++i) {
            const Vec3d c = ice.centre_m(i, j, k);
            const Vec3d q = c + off;
            double T;
            if (k == k_top || q.x() < lo.x() || q.x() > hi.x() || q.y() < lo.y() || q.y() > hi.y()) {
              T = march_T(c, to_lamp);
            } else {
              // Bilinear in layer k + 1 (clamped to its centres) times Simpson's rule on the step.
              const double gx = std::clamp((q.x() - ice.origin_m.x()) / h - 0.5, 0.0, ice.nx - 1.0);
              const double gy = std::clamp((q.y() - ice.origin_m.y()) / h - 0.5, 0.0, ice.ny - 1.0);
              const int i0 = std::min(int(gx), ice.nx - 1), j0b = std::min(int(gy), ice.ny - 1);
              const int i1 = std::min(i0 + 1, ice.nx - 1), j1b = std::min(j0b + 1, ice.ny - 1);
              const double tx = gx - i0, ty = gy - j0b;
              auto Tu = [&](int a, int b) { return double(lamp_T.at(a, b, k + 1)); };
              const double up = (Tu(i0, j0b) * (1 - tx) + Tu(i1, j0b) * tx) * (1 - ty) +
                                (Tu(i0, j1b) * (1 - tx) + Tu(i1, j1b) * tx) * ty;
              const double f = (ice.sample(c) + 4.0 * ice.sample(c + 0.5 * off) + ice.sample(q)) / 6.0;
              T = up * std::exp(-opt.extinction_per_m * f * len);
            }
            lamp_T.at(i, j, k) = float(T);
          }
      };
      if (opt.parallel) {
        tbb::parallel_for(tbb::blocked_range<int>(0, ice.ny, 8),
                          [&](const tbb::blocked_range<int>& r) { layer(r.begin(), r.end()); });
      } else {
        layer(0, ice.ny);
      }
    }
  }

  double lamp_T_at(const Vec3d& x) const {
    switch (opt.shadow) {
      case IcePhotoOptions::Shadow::kNone: return 1.0;
      case IcePhotoOptions::Shadow::kMarch: return march_T(x, to_lamp);
      case IcePhotoOptions::Shadow::kGrid: return lamp_T.empty() ? 1.0 : lamp_T.sample(x, 1.0);
    }
    return 1.0;
  }

  /// Linear RGB radiance along the ray o + t d (d unit).
  std::array<double, 3> trace(const Vec3d& o, const Vec3d& d) const {
    std::array<double, 3> rad{0, 0, 0};
    double T = 1.0;
    double t_ground = kInf;
    if (d.z() < 0.0) t_ground = (opt.ground_z_m - o.z()) / d.z();
    if (t_ground < 0.0) t_ground = kInf;  // camera below the ground: no ground in view
    double t0 = 0, t1 = 0;
    if (opt.extinction_per_m > 0 && slab(box, o, d, t0, t1)) {
      t0 = std::max(t0, 0.0);
      t1 = std::min(t1, t_ground);
      if (t1 > t0) {
        const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
        const double dt = (t1 - t0) / n;
        const double p = henyey_greenstein(to_lamp.dot(d), opt.hg_g);
        const bool scatter = opt.albedo > 0.0;
        for (int i = 0; i < n; ++i) {
          const Vec3d x = o + (t0 + (i + 0.5) * dt) * d;
          const double f = ice.sample(x);
          if (f <= 0.0) continue;
          const double att = std::exp(-opt.extinction_per_m * f * dt);
          if (scatter) {
            // ∫ over the step of a σ (L p T_lamp + sky) e^{-σ s} ds = a (L p T_lamp + sky)(1 - att)
            const double s = (opt.lamp_irradiance * p * lamp_T_at(x) + opt.sky_radiance) * (1.0 - att) * T;
            for (std::size_t c = 0; c < 3; ++c) rad[c] += a_rgb[c] * s;
          }
          T *= att;
          if (T < opt.min_transmittance) return rad;
        }
      }
    }
    if (t_ground == kInf) {  // the sky
      for (auto& r : rad) r += T * opt.sky_radiance;
      return rad;
    }
    const Vec3d g = o + t_ground * d;
    const double rho = opt.ground_albedo *
                       std::max(0.0, 1.0 + opt.ground_texture_contrast *
                                               ground_texture(g.x(), g.y(), opt.ground_texture_scale_m, opt.ground_seed));
    double Tl = 1.0, Tz = 1.0;
    if (opt.shadow != IcePhotoOptions::Shadow::kNone && opt.extinction_per_m > 0) {
      Tl = march_T(g, to_lamp);
      Tz = march_T(g, Vec3d(0, 0, 1));
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

double top_of_scene(const IceFraction& ice, double ground_z) {
  return std::max(ice.max_m().z(), ground_z) + 1.0;
}

}  // namespace

double henyey_greenstein(double cos_theta, double g) {
  const double denom = 1.0 + g * g - 2.0 * g * cos_theta;
  return (1.0 - g * g) / (4.0 * std::numbers::pi * denom * std::sqrt(denom));
}

double ground_texture(double x_m, double y_m, double scale_m, std::uint64_t seed) {
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
      return 2.0 * to_unit(hash3(seed * 8 + std::uint64_t(oct), std::uint64_t(a), std::uint64_t(b))) - 1.0;
    };
    const double v = (lat(ix, iy) * (1 - tx) + lat(ix + 1, iy) * tx) * (1 - ty) +
                     (lat(ix, iy + 1) * (1 - tx) + lat(ix + 1, iy + 1) * tx) * ty;
    sum += amp * v;
    norm += amp;
    amp *= 0.5;
    freq *= 2.0;
  }
  return sum / norm;
}

cv::Mat render_ice_radiance(const IceFraction& ice, const Camera& camera, const IcePhotoOptions& options) {
  const Scene scene(ice, options);
  const int W = camera_width(camera), H = camera_height(camera);
  const RayGen gen(camera, top_of_scene(ice, options.ground_z_m));
  const int k = options.supersample;
  cv::Mat out(H, W, CV_32FC3, cv::Scalar::all(0));
  for_rows(H, options.parallel, [&](int v) {
    auto* row = out.ptr<cv::Vec3f>(v);
    for (int u = 0; u < W; ++u) {
      std::array<double, 3> acc{0, 0, 0};
      for (int t = 0; t < k; ++t)
        for (int s = 0; s < k; ++s) {
          Vec3d o, d;
          if (!gen.ray(u - 0.5 + (s + 0.5) / k, v - 0.5 + (t + 0.5) / k, o, d)) continue;
          const auto r = scene.trace(o, d);
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
          const std::uint64_t id = (std::uint64_t(v) * std::uint64_t(lin.cols) + std::uint64_t(u)) * 3 + std::uint64_t(c);
          const std::uint64_t h = hash3(options.seed, id, 0x6e6f697365ull);
          const double u1 = to_unit(h), u2 = to_unit(splitmix64(h));
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
  const RayGen gen(camera, top_of_scene(ice, ground_z_m));
  const double step = ice.h_m / 8.0;
  for_rows(H, true, [&](int v) {
    auto* row = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < W; ++u) {
      Vec3d o, d;
      if (!gen.ray(u, v, o, d)) continue;
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
  cv::Mat pixels;
  if (image.channels() == 3) {
    cv::cvtColor(image, pixels, cv::COLOR_BGR2RGB);
  } else {
    pixels = image.isContinuous() ? image : image.clone();
  }
  write_atomically(file, [&](const std::filesystem::path& tmp) {
    auto out = OIIO::ImageOutput::create("jpg");
    if (!out) throw InputError(fmt::format("{}: cannot write JPEG: {}", file.string(), OIIO::geterror()));
    OIIO::ImageSpec spec(pixels.cols, pixels.rows, pixels.channels(), OIIO::TypeDesc::UINT8);
    spec.attribute("Compression", fmt::format("jpeg:{}", quality));
    spec.attribute("CompressionQuality", quality);
    bool ok = out->open(tmp.string(), spec);
    if (ok) ok = out->write_image(OIIO::TypeDesc::UINT8, pixels.data);
    const bool closed = out->close();
    std::string err = out->geterror();
    if (err.empty()) err = OIIO::geterror();
    if (!ok || !closed || !err.empty())
      throw InputError(fmt::format("{}: cannot write JPEG: {}", file.string(), err));
  });
}

}  // namespace meltlab::render
