#pragma once
// MIP-mapped, anisotropically filtered lookups of the renderer's image assets through
// OpenImageIO's TextureSystem (scene `texture_filter: mipmap`).
//
// The TextureSystem reads tiled, MIP-mapped files: each registered image (procedural or read
// from a file; cube maps already resampled to lat-long) is written as one with
// ImageBufAlgo::make_texture (float texels, 64×64 tiles, box-filtered levels, TIFF: an
// OpenEXR file would carry OpenEXR's y-up, border-sampled lat-long convention) into a private
// temporary directory; the destructor invalidates the files in the cache and removes them.
// All instances share one process-wide TextureSystem that is never destroyed (see the .cpp).
// Cost (bench_render BM_TextureLookup): ~0.6 µs per point lookup and ~1.5 µs per 8:1
// anisotropic one, against ~30 ns for sample_bilinear_rgb.
//
// Conventions equal the bilinear path of texture/assets.h, so that a lookup with a zero
// footprint is the bilinear lookup of the finest level (tested):
//   * 2D textures at (s, t) in texture periods, texel (i, j) at ((i + ½)/w, (j + ½)/h),
//     periodic in both directions (sample_bilinear_rgb repeating in both);
//   * lat-long environments in OpenImageIO's z-up convention, which is sample_latlong's.
// Footprints are the derivatives of the lookup coordinates per pixel step in x and in y
// (d(s,t)/dx, d(s,t)/dy; dR/dx, dR/dy for environments), from ray differentials.
// Lookups are thread-safe (the TextureSystem keeps per-thread state).

#include <meltlab/render/texture/assets.h>

#include <Eigen/Core>

#include <memory>
#include <string>

namespace meltlab::render {

class FilteredTextures {
 public:
  enum class Kind { kTexture, kLatLongEnvironment };

  FilteredTextures();
  ~FilteredTextures();
  FilteredTextures(const FilteredTextures&) = delete;
  FilteredTextures& operator=(const FilteredTextures&) = delete;

  /// Makes a MIP-mapped texture of `image` and returns its id for the lookups. `name` is for
  /// messages. Throws InputError if OpenImageIO cannot make or open it.
  int add(const RgbImage& image, Kind kind, const std::string& name);

  /// Filtered lookup of a 2D texture at (s, t) with footprint derivatives (periods per pixel).
  Eigen::Vector3d texture(int id, double s, double t, const Eigen::Vector2d& dst_dx,
                          const Eigen::Vector2d& dst_dy) const;
  /// Filtered lookup of a lat-long environment in direction `dir` (any length > 0).
  Eigen::Vector3d environment(int id, const Eigen::Vector3d& dir, const Eigen::Vector3d& ddir_dx,
                              const Eigen::Vector3d& ddir_dy) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meltlab::render
