#pragma once
// The renderer's image textures behind one lookup interface, whatever the scene's
// `texture_filter`:
//   bilinear  point-sampled bilinear lookups of the finest level (sample_bilinear_rgb,
//             sample_latlong; the monograph's GPU lookups); footprints are ignored;
//   mipmap    MIP-mapped, anisotropic lookups through OpenImageIO's TextureSystem
//             (texture/filtered.h) with the footprint of the lookup (ray_differential.h); a
//             lookup without a footprint reads the finest level.
// The two agree for a zero footprint (tests/render/ice/texture_filter_test.cpp), so a caller
// passes the footprint it has and never asks which filter is on; only the integrator asks,
// once, whether footprints are worth computing (TextureFactory::uses_footprints).
// Lookups are const and thread-safe.

#include <meltlab/render/ray_differential.h>
#include <meltlab/render/texture/assets.h>

#include <Eigen/Core>

#include <memory>
#include <string>

namespace meltlab::render {

class FilteredTextures;

/// How the renderer looks its image assets up (environment, ground texture, normal map, ice texture).
enum class TextureFilter {
  kBilinear,  ///< point-sampled bilinear at the finest level (the monograph's GPU lookups)
  kMipmap,    ///< OpenImageIO's TextureSystem: MIP-mapped, anisotropic, footprints from ray differentials
};

/// A tiled image at (s, t) in texture periods, periodic in both directions; texel (i, j) at
/// ((i + ½)/w, (j + ½)/h).
class ImageTexture {
 public:
  virtual ~ImageTexture() = default;
  /// `footprint`: d(s,t)/dx, d(s,t)/dy in periods per pixel step; nullptr: the finest level.
  virtual Rgb lookup(const Eigen::Vector2d& st, const Differential2* footprint) const = 0;
};

/// A lat-long environment (texture/assets.h's convention, z up) looked up by direction.
class EnvironmentTexture {
 public:
  virtual ~EnvironmentTexture() = default;
  /// `dir` any length > 0; `footprint`: its change per pixel step; nullptr: the finest level.
  virtual Rgb lookup(const Eigen::Vector3d& dir, const Differential* footprint) const = 0;
};

/// Makes the textures of one renderer, all with one filter. The MIP-mapped ones share one
/// FilteredTextures, which lives as long as the last of them.
class TextureFactory {
 public:
  explicit TextureFactory(TextureFilter filter);
  ~TextureFactory();
  /// `name` is for messages. Throws InputError if a MIP-mapped texture cannot be made.
  std::unique_ptr<const ImageTexture> image(RgbImage image, const std::string& name);
  std::unique_ptr<const EnvironmentTexture> environment(RgbImage latlong, const std::string& name);
  /// Whether the lookups use footprints (mipmap): the integrator computes ray differentials only then.
  bool uses_footprints() const { return filter_ == TextureFilter::kMipmap; }

 private:
  TextureFilter filter_;
  std::shared_ptr<FilteredTextures> filtered_;  ///< mipmap only
};

/// The projection axis of a triplanar mapping: the dominant axis (0, 1, 2) of the normal `ng`.
int dominant_axis(const Eigen::Vector3d& ng);

/// An image projected along world axis `axis` (0, 1, 2) with period `tile` (mesh units), at the
/// point x: (s, t) = (y, z), (x, z) or (x, y) / tile. `dx`: the footprint of x (nullptr: none).
Rgb lookup_projected(const ImageTexture& texture, const Eigen::Vector3d& x, int axis, double tile,
                     const Differential* dx);

}  // namespace meltlab::render
