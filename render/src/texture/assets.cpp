// Procedural assets and image files of the ice/liquid renderer (texture/assets.h).

#include <meltlab/render/texture/assets.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace meltlab::render {

using Eigen::Vector3d;

namespace {

double hash01(std::int64_t x, std::int64_t y, std::int64_t z, std::uint64_t seed) {
  std::uint64_t h = seed * 0x9E3779B97F4A7C15ull;
  for (std::int64_t v : {x, y, z}) {
    h ^= static_cast<std::uint64_t>(v) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
  }
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}
double smooth(double t) { return t * t * (3 - 2 * t); }

// Value noise on a lattice of period `period` cells in x and y (tileable), in [0, 1].
double periodic_noise(double x, double y, int period, std::uint64_t seed) {
  const double x0 = std::floor(x), y0 = std::floor(y);
  const double fx = smooth(x - x0), fy = smooth(y - y0);
  auto h = [&](double i, double j) {
    const auto pi = static_cast<std::int64_t>(i), pj = static_cast<std::int64_t>(j);
    return hash01(((pi % period) + period) % period, ((pj % period) + period) % period, 0, seed);
  };
  const double a = h(x0, y0), b = h(x0 + 1, y0), c = h(x0, y0 + 1), d = h(x0 + 1, y0 + 1);
  return (1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * c + fx * d);
}
double periodic_fbm(double u, double v, int base_period, std::uint64_t seed) {
  double s = 0, amp = 0.5, norm = 0;
  int period = base_period;
  for (int o = 0; o < 4; ++o) {
    s += amp * periodic_noise(u * period, v * period, period, seed + static_cast<std::uint64_t>(o));
    norm += amp;
    amp *= 0.5;
    period *= 2;
  }
  return s / norm;
}

double value_noise3(const Vector3d& p, std::uint64_t seed) {
  const Vector3d f0 = p.array().floor();
  const Vector3d f = p - f0;
  const Vector3d w(smooth(f.x()), smooth(f.y()), smooth(f.z()));
  const auto x = static_cast<std::int64_t>(f0.x()), y = static_cast<std::int64_t>(f0.y()),
             z = static_cast<std::int64_t>(f0.z());
  double s = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double wt = (dx ? w.x() : 1 - w.x()) * (dy ? w.y() : 1 - w.y()) * (dz ? w.z() : 1 - w.z());
    s += wt * hash01(x + dx, y + dy, z + dz, seed);
  }
  return s;
}

// The direction through the centre of texel (i, j) of a w x h lat-long map (the inverse of
// sample_latlong's mapping).
Vector3d latlong_texel_direction(int i, int j, int w, int h) {
  const double theta = (j + 0.5) / h * std::numbers::pi;  // from the zenith
  const double phi = ((i + 0.5) / w - 0.5) * 2 * std::numbers::pi;
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

}  // namespace

RgbImage latlong_environment(const EnvironmentOptions& o) {
  RgbImage env = rgb_image(o.width, o.height);
  if (o.constant >= 0) {
    std::fill(env.values().begin(), env.values().end(), static_cast<float>(o.constant));
    return env;
  }
  const Vector3d sun = o.to_sun.normalized();
  const double sun_cos = std::cos(1.5 * std::numbers::pi / 180.0);
  for (int j = 0; j < o.height; ++j) {
    for (int i = 0; i < o.width; ++i) {
      const Vector3d d = latlong_texel_direction(i, j, o.width, o.height);
      const double phi = ((i + 0.5) / o.width - 0.5) * 2 * std::numbers::pi;  // d's longitude, as computed there
      Vector3d c;
      if (d.z() >= 0) {
        const double t = std::pow(1.0 - d.z(), 3.0);
        c = (1 - t) * o.zenith + t * o.horizon;
        // Bright windows: 8 vertical panels between 3° and 25° elevation.
        const double elev = std::asin(d.z()) * 180.0 / std::numbers::pi;
        const double panel = std::fmod((phi / (2 * std::numbers::pi) + 1.0) * 8.0, 1.0);
        if (elev > 3 && elev < 25 && panel > 0.15 && panel < 0.45) c = Vector3d(2.5, 2.4, 2.2);
        const double cs = d.dot(sun);
        if (cs > sun_cos)
          c = Vector3d::Constant(o.sun_radiance);
        else
          c += Vector3d(1.0, 0.9, 0.7) * 0.6 * std::pow(std::max(0.0, cs), 64.0);  // glow
      } else {
        // A checkered floor seen from the centre of a room (2 m below, 1 m squares).
        const double r = 2.0 / std::max(1e-3, -d.z());
        const int check = (static_cast<int>(std::floor(d.x() * r)) + static_cast<int>(std::floor(d.y() * r))) & 1;
        c = o.floor * (check ? 1.0 : 1.0 - o.floor_checker);
      }
      set_rgb(env, i, j, c);
    }
  }
  return env;
}

Vector3d sample_latlong(const RgbImage& env, const Vector3d& dir) {
  const Vector3d d = dir.normalized();
  const double u = std::atan2(d.y(), d.x()) / (2 * std::numbers::pi) + 0.5;
  const double v = std::acos(std::clamp(d.z(), -1.0, 1.0)) / std::numbers::pi;
  return sample_bilinear_rgb(env, u * env.width() - 0.5, v * env.height() - 0.5, ImageWrap::kRepeat, ImageWrap::kClamp);
}

RgbImage ground_texture(int size, std::uint64_t seed) {
  RgbImage img = rgb_image(size, size);
  const Vector3d light(0.62, 0.58, 0.52), dark(0.42, 0.40, 0.37), grout(0.25, 0.24, 0.22);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const double u = (i + 0.5) / size, v = (j + 0.5) / size;
      const double n = periodic_fbm(u, v, 8, seed);
      // 4 x 4 tiles per texture period, alternating tones, thin grout lines.
      const double tu = u * 4, tv = v * 4;
      const bool alt = ((static_cast<int>(tu) + static_cast<int>(tv)) & 1) != 0;
      const double eu = std::min(tu - std::floor(tu), std::ceil(tu) - tu),
                   ev = std::min(tv - std::floor(tv), std::ceil(tv) - tv);
      Vector3d c = (alt ? light : dark) * (0.75 + 0.5 * n);
      if (std::min(eu, ev) < 0.025) c = grout;
      set_rgb(img, i, j, c.cwiseMin(1.0));
    }
  return img;
}

RgbImage normal_map(int size, double bump, std::uint64_t seed) {
  RgbImage img = rgb_image(size, size);
  auto height = [&](int i, int j) {
    return periodic_fbm((((i % size) + size) % size + 0.5) / size, (((j % size) + size) % size + 0.5) / size, 6, seed);
  };
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      // Slopes of the height field (height range 1 over a texture period of 1 → × size/2).
      const double dx = (height(i + 1, j) - height(i - 1, j)) * 0.5 * size * bump / 16.0;
      const double dy = (height(i, j + 1) - height(i, j - 1)) * 0.5 * size * bump / 16.0;
      const Vector3d n = Vector3d(-dx, -dy, 1.0).normalized();
      set_rgb(img, i, j, 0.5 * n + Vector3d::Constant(0.5));  // inverse of Eq. 6.12
    }
  return img;
}

double milky_ice(const Vector3d& p, double scale) {
  const Vector3d q = p / scale;
  const double n = 0.5 * value_noise3(q, 7) + 0.3 * value_noise3(2.03 * q, 8) + 0.2 * value_noise3(4.11 * q, 9);
  return std::clamp(0.55 + 0.6 * (n - 0.5) + 0.25, 0.0, 1.0);  // mostly bright, cloudy
}

// ---- files ----------------------------------------------------------------------------

void write_exr(const std::filesystem::path& file, const RgbImage& image) { write_image(file, image); }

void write_png(const std::filesystem::path& file, const RgbImage& image, double exposure, double gamma) {
  Image8 px(image.width(), image.height(), 3);
  for (std::size_t k = 0; k < px.size(); ++k) {
    const double x = std::clamp(exposure * static_cast<double>(image.values()[k]), 0.0, 1.0);
    px.values()[k] = static_cast<std::uint8_t>(std::lround(std::pow(x, 1.0 / gamma) * 255.0));
  }
  write_image(file, px);
}

void write_gray_png(const std::filesystem::path& file, const std::vector<float>& values, int width, int height,
                    float white, bool flip_y) {
  Image8 px(width, height, 1);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const int src_row = flip_y ? height - 1 - j : j;
      const double x = static_cast<double>(values[static_cast<std::size_t>(src_row) * width + i] / white);
      px.at(i, j) = static_cast<std::uint8_t>(std::lround(std::clamp(x, 0.0, 1.0) * 255.0));
    }
  write_image(file, px);
}

RgbImage read_rgb_image(const std::filesystem::path& file) {
  // OpenImageIO's default alpha handling (colours multiplied by alpha), as this reader always had.
  const ImageF px = read_image(file, input_limits().image_pixels, ImageAlpha::kAssociated);
  RgbImage img = rgb_image(px.width(), px.height());
  const int grey = px.channels() < 3;  // 1 or 2 channels: grey (+ alpha)
  for (int j = 0; j < px.height(); ++j)
    for (int i = 0; i < px.width(); ++i)
      for (int c = 0; c < 3; ++c) {
        const float v = px.at(i, j, grey ? 0 : c);
        if (!std::isfinite(v))
          throw InputError(fmt::format("{}: pixel {} is not finite", file.string(),
                                       static_cast<std::size_t>(j) * static_cast<std::size_t>(px.width()) + i));
        img.at(i, j, c) = v;
      }
  return img;
}

RgbImage read_png(const std::filesystem::path& file) { return read_rgb_image(file); }

// ---- environment files ----------------------------------------------------------------

namespace {

// Faces in the order px nx py ny pz nz; each at cell (col, row) of a layout of cols x rows
// square cells, `rotated` = stored turned by 180°.
struct CubeCell {
  int col = 0, row = 0;
  bool rotated = false;
};
struct CubeGeometry {
  int cols = 0, rows = 0;
  std::array<CubeCell, 6> cells;
};

CubeGeometry cube_geometry(EnvironmentLayout layout) {
  switch (layout) {
    case EnvironmentLayout::kCube3x2:
      return {3, 2, {{{0, 0}, {0, 1}, {1, 0}, {1, 1}, {2, 0}, {2, 1}}}};
    case EnvironmentLayout::kCube1x6:
      return {1, 6, {{{0, 0}, {0, 1}, {0, 2}, {0, 3}, {0, 4}, {0, 5}}}};
    case EnvironmentLayout::kCrossHorizontal:
      return {4, 3, {{{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {3, 1}}}};
    case EnvironmentLayout::kCrossVertical:
      return {3, 4, {{{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {1, 3, true}}}};
    default:
      throw InvariantError("cube_geometry: not a cube-map layout");
  }
}

// The face of cube-frame direction c and its coordinates on it, s to the right and t down,
// in [0, 1] (the face table of texture/assets.h).
void cube_face(const Vector3d& c, int& face, double& s, double& t) {
  const Vector3d a = c.cwiseAbs();
  double sc = 0, tc = 0, major = 0;
  if (a.x() >= a.y() && a.x() >= a.z()) {
    major = a.x();
    face = c.x() > 0 ? 0 : 1;
    sc = c.x() > 0 ? -c.z() : c.z();
    tc = -c.y();
  } else if (a.y() >= a.z()) {
    major = a.y();
    face = c.y() > 0 ? 2 : 3;
    sc = c.x();
    tc = c.y() > 0 ? c.z() : -c.z();
  } else {
    major = a.z();
    face = c.z() > 0 ? 4 : 5;
    sc = c.z() > 0 ? c.x() : -c.x();
    tc = -c.y();
  }
  s = 0.5 * (sc / major + 1.0);
  t = 0.5 * (tc / major + 1.0);
}

RgbImage latlong_from_cube(const RgbImage& img, EnvironmentLayout layout, const std::filesystem::path& file) {
  const CubeGeometry g = cube_geometry(layout);
  const int F = img.width() / g.cols;
  if (F < 1 || img.width() != g.cols * F || img.height() != g.rows * F)
    throw InputError(fmt::format("{}: a {} cube map must be {} x {} square faces, not {} x {} pixels", file.string(),
                                 environment_layout_name(layout), g.cols, g.rows, img.width(), img.height()));
  // The six faces as images of their own (a rotated cell turned upright), so each lookup
  // clamps at its face's edge texels.
  std::array<RgbImage, 6> faces;
  for (int face = 0; face < 6; ++face) {
    const CubeCell& cell = g.cells[static_cast<std::size_t>(face)];
    faces[static_cast<std::size_t>(face)] = rgb_image(F, F);
    for (int y = 0; y < F; ++y)
      for (int x = 0; x < F; ++x) {
        const int sx = cell.rotated ? F - 1 - x : x, sy = cell.rotated ? F - 1 - y : y;
        for (int c = 0; c < 3; ++c)
          faces[static_cast<std::size_t>(face)].at(x, y, c) = img.at(cell.col * F + sx, cell.row * F + sy, c);
      }
  }
  RgbImage out = rgb_image(4 * F, 2 * F);
  for (int j = 0; j < out.height(); ++j) {
    for (int i = 0; i < out.width(); ++i) {
      const Vector3d d = latlong_texel_direction(i, j, out.width(), out.height());
      int face = 0;
      double s = 0, t = 0;
      cube_face(Vector3d(-d.y(), d.z(), d.x()), face, s, t);  // world -> the cube's y-up frame
      // Clamped to the face's texel centres first (not only the neighbours, as kClamp does):
      // outside them the lookup returns the edge texel itself rather than a blend of it with itself.
      const double x = std::clamp(s * F - 0.5, 0.0, F - 1.0), y = std::clamp(t * F - 0.5, 0.0, F - 1.0);
      set_rgb(out, i, j,
              sample_bilinear_rgb(faces[static_cast<std::size_t>(face)], x, y, ImageWrap::kClamp, ImageWrap::kClamp));
    }
  }
  return out;
}

}  // namespace

const char* environment_layout_name(EnvironmentLayout layout) {
  switch (layout) {
    case EnvironmentLayout::kAuto:
      return "auto";
    case EnvironmentLayout::kLatLong:
      return "latlong";
    case EnvironmentLayout::kCube3x2:
      return "cube_3x2";
    case EnvironmentLayout::kCube1x6:
      return "cube_1x6";
    case EnvironmentLayout::kCrossHorizontal:
      return "cross_horizontal";
    case EnvironmentLayout::kCrossVertical:
      return "cross_vertical";
  }
  return "?";
}

std::optional<EnvironmentLayout> environment_layout_from_name(const std::string& name) {
  for (auto l : {EnvironmentLayout::kAuto, EnvironmentLayout::kLatLong, EnvironmentLayout::kCube3x2,
                 EnvironmentLayout::kCube1x6, EnvironmentLayout::kCrossHorizontal, EnvironmentLayout::kCrossVertical})
    if (name == environment_layout_name(l)) return l;
  return std::nullopt;
}

RgbImage read_environment(const std::filesystem::path& file, EnvironmentLayout layout) {
  RgbImage img = read_rgb_image(file);
  if (layout == EnvironmentLayout::kAuto) {
    const int w = img.width(), h = img.height();
    if (w == 2 * h)
      layout = EnvironmentLayout::kLatLong;
    else if (2 * w == 3 * h)
      layout = EnvironmentLayout::kCube3x2;
    else if (h == 6 * w)
      layout = EnvironmentLayout::kCube1x6;
    else if (3 * w == 4 * h)
      layout = EnvironmentLayout::kCrossHorizontal;
    else if (4 * w == 3 * h)
      layout = EnvironmentLayout::kCrossVertical;
    else
      throw InputError(
          fmt::format("{}: a {} x {} environment is neither a 2:1 lat-long map nor a cube map (3:2, 1:6, 4:3, 3:4); "
                      "set environment.layout",
                      file.string(), w, h));
  }
  return layout == EnvironmentLayout::kLatLong ? img : latlong_from_cube(img, layout, file);
}

}  // namespace meltlab::render
