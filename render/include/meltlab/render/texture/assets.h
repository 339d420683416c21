#pragma once
// Procedural default assets of the ice/liquid renderer, generated in code so nothing is
// downloaded: a lat-long environment (sky, sun, a room-like horizon), a tileable ground
// texture, a tileable normal map (stored encoded as Eq. 6.12 expects) and a solid "milky ice"
// texture standing in for the monograph's photograph tdiff (§6.1).
//
// Directions are world vectors with z up. Lat-long: u = atan2(y, x)/2π + ½ (column),
// v = acos(z)/π (row 0 = zenith). Images are row-major RGB float, linear.

#include <meltlab/core/image.h>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::render {

/// A linear RGB colour (radiance, a texel, a material's weights per channel).
using Rgb = Eigen::Vector3d;
/// Linear RGB float image: meltlab's image type with 3 channels (lookups: sample_bilinear_rgb).
using RgbImage = ImageF;
/// A w x h RGB image of zeros.
inline RgbImage rgb_image(int w, int h) { return RgbImage(w, h, 3); }
/// Pixel (i, j) of an RGB image as a colour, and the reverse.
inline Eigen::Vector3d rgb_at(const RgbImage& img, int i, int j) {
  const float* p = &img.at(i, j);
  return {static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])};
}
inline void set_rgb(RgbImage& img, int i, int j, const Eigen::Vector3d& c) {
  float* p = &img.at(i, j);
  p[0] = static_cast<float>(c.x());
  p[1] = static_cast<float>(c.y());
  p[2] = static_cast<float>(c.z());
}

/// How an environment image file stores directions.
///   lat-long: 2:1, the convention above (OpenImageIO's z-up lat-long).
///   Cube maps: six square faces with OpenImageIO's (= OpenGL's) face table in a y-up frame
///   (face: major axis, +column, +row): px +x -z -y, nx -x +z -y, py +y +x +z, ny -y +x -z,
///   pz +z +x -y, nz -z -x -y. World direction (x, y, z) reads the cube at (-y, z, x): the
///   relation of OpenImageIO's y-up and z-up lat-long maps, so a cube map and the lat-long map
///   of the same y-up environment (OpenEXR's envmap conventions) render alike.
///     cube_3x2: px py pz / nx ny nz (OpenImageIO, RenderMan)
///     cube_1x6: px nx py ny pz nz stacked vertically (OpenEXR envmap=cube)
///     cross_horizontal: 4x3 cells, py above pz, row nx pz px nz, ny below pz
///     cross_vertical: 3x4 cells, py; nx pz px; ny; nz rotated by 180° at the bottom
///   auto: by the aspect ratio (2:1, 3:2, 1:6, 4:3, 3:4), anything else is refused.
enum class EnvironmentLayout { kAuto, kLatLong, kCube3x2, kCube1x6, kCrossHorizontal, kCrossVertical };

struct EnvironmentOptions {
  int width = 512, height = 256;
  Eigen::Vector3d to_sun = Eigen::Vector3d(0.5, -0.4, 0.75);  ///< normalised on use
  double sun_radiance = 30.0;                                 ///< the sun disc (≈ 1.5° radius)
  Eigen::Vector3d zenith{0.25, 0.45, 0.95}, horizon{0.85, 0.9, 1.0}, floor{0.18, 0.16, 0.14};
  double floor_checker = 0.4;  ///< dark squares are floor·(1 - floor_checker)
  double constant = -1.0;      ///< >= 0: a uniform map of this radiance (a "white furnace")
  std::filesystem::path file;  ///< non-empty: a lat-long or cube map read from this image instead
  EnvironmentLayout layout = EnvironmentLayout::kAuto;  ///< how `file` stores the directions
};
/// Lat-long environment: sky gradient, sun disc, bright vertical "windows" just above the
/// horizon (so reflections and refractions show structure) and a checkered floor below it.
RgbImage latlong_environment(const EnvironmentOptions& options = {});
/// Bilinear lookup of a lat-long map in direction `dir` (any length > 0).
Eigen::Vector3d sample_latlong(const RgbImage& env, const Eigen::Vector3d& dir);

/// Tileable ground texture in [0, 1]: stone tiles of two tones modulated by value noise.
RgbImage ground_texture(int size = 256, std::uint64_t seed = 1);
/// Tileable normal map encoded in [0, 1] (rgb = N/2 + ½, Eq. 6.12 inverted) from a noise
/// height field; `bump` scales the slopes (0 = flat, rgb = (½, ½, 1)).
RgbImage normal_map(int size = 256, double bump = 1.0, std::uint64_t seed = 2);
/// Solid milky-ice texture in [0, 1] at a world point (mesh units); `scale` = feature size.
double milky_ice(const Eigen::Vector3d& p, double scale);

/// Writes linear RGB as OpenEXR (half float), atomically. Throws InputError on failure.
void write_exr(const std::filesystem::path& file, const RgbImage& image);
/// Writes 8-bit PNG: v = clamp(exposure·x)^(1/gamma), atomically.
void write_png(const std::filesystem::path& file, const RgbImage& image, double exposure = 1.0, double gamma = 2.2);
/// Writes a one-channel float grid (row 0 = y max, i.e. the ground seen from above) as an
/// 8-bit gray PNG: clamp(value / white)·255.
void write_gray_png(const std::filesystem::path& file, const std::vector<float>& values, int width, int height,
                    float white = 1.0f, bool flip_y = true);
/// Reads any image meltlab::read_image reads (EXR, HDR, PNG, JPEG, TIFF, ...) as RGB floats: the
/// stored values (linear for EXR/HDR; 8- and 16-bit files normalised to [0, 1] without a
/// colour transform), grey replicated, alpha and extra channels dropped. Throws InputError
/// naming the file if it cannot be read or holds no pixels.
RgbImage read_rgb_image(const std::filesystem::path& file);
/// The lat-long environment stored in `file` in `layout`. Cube maps are resampled to a
/// lat-long map of 4F x 2F texels (F = face size; the equator keeps the faces' texel
/// density), bilinear within each face with its edge texels clamped. Throws InputError naming
/// the file if it cannot be read or its size does not fit the layout.
RgbImage read_environment(const std::filesystem::path& file, EnvironmentLayout layout = EnvironmentLayout::kAuto);
/// The layout's name in scene files (latlong, cube_3x2, ...; auto) and back (nullopt if unknown).
const char* environment_layout_name(EnvironmentLayout layout);
std::optional<EnvironmentLayout> environment_layout_from_name(const std::string& name);

/// read_rgb_image of an 8-bit PNG (the reference-image tests).
RgbImage read_png(const std::filesystem::path& file);

}  // namespace meltlab::render
