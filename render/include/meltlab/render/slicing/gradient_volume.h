#pragma once
// Seed 003's gradient ("normal") volume (spec ../shared/spec/volume-slicing-importance.md §2.2,
// §2.3): per voxel c, over the integer offsets o ≠ 0 of a neighbourhood of radius r,
//   g(c) = Σ_o (o / |o|) (f(c + o) - f(c))        (index units; neighbours clamped: vsi.grad.boundary)
// pointing towards increasing value. For a linear field f = a · x it is exactly k_r a with
// k_r = Σ o_x² / |o| (cube: k1 = 2 + 8/√2 + 8/√3 ≈ 12.276, k2 ≈ 98.311).
//
// Encoding (vsi.grad.encode, vsi.grad.bits): e = 1/2 + 1/2 g / max_c |g| per component, quantised
// to 2^bits - 1 levels (8: the source's RGB8; 4: its rejected RGBA4), three channels per voxel,
// interleaved. Decoding: g' = 2 e - 1 (|g'| ≤ 1 up to quantisation; times max |g| for the raw
// value). The renderer interpolates the encoded channels trilinearly (as the GPU filters the
// texture) and decodes.
//
// Cache (the source caches normals in a binary file on first use): a file named by the content
// hash of the volume's samples, placement and the options, in a cache folder the caller names
// (experiments: <dataset cache>/slicing-gradients); its size and header are checked on read, a
// bad file is recomputed and replaced.

#include <meltlab/render/volume/volume.h>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace meltlab::render {

/// vsi.grad.neighbourhood.
enum class GradientNeighbourhood {
  kCube,  ///< [-r, r]³ without 0 (the harness's default)
  kBall,  ///< the offsets of the cube with |o| <= r
};

struct GradientOptions {
  int radius = 2;  ///< vsi.grad.radius: 1 or 2 (larger radii allowed up to 4)
  GradientNeighbourhood neighbourhood = GradientNeighbourhood::kCube;
  int bits = 8;  ///< vsi.grad.bits: 8 or 4
};

/// k_r = Σ o_x² / |o| of the neighbourhood (the estimator's gain on linear fields).
double gradient_normaliser(int radius, GradientNeighbourhood neighbourhood);

/// The raw estimate g at every voxel (x fastest; 3 floats per voxel), in value per index unit times k_r.
std::vector<Eigen::Vector3f> estimate_gradients(const Volume& volume, int radius, GradientNeighbourhood neighbourhood);

/// An encoded gradient volume over the same samples as its data volume.
struct GradientVolume {
  std::array<int, 3> dims{0, 0, 0};
  GradientOptions options;
  double max_magnitude = 0;           ///< max_c |g| (raw, the decode scale)
  std::vector<std::uint8_t> encoded;  ///< 3 per voxel, x fastest, values 0 .. 2^bits - 1
  bool from_cache = false;            ///< read from the cache file (not computed)
  double build_ms = 0;                ///< time to compute or read

  int levels() const { return (1 << options.bits) - 1; }
  /// The typed view of channel c (0..2) for trilinear lookups (value = e ∈ [0, 1]).
  VolumeSamples<std::uint8_t> channel(int c) const;
  /// The decoded direction-and-magnitude vector 2e - 1 at voxel (i, j, k).
  Eigen::Vector3d decoded(int i, int j, int k) const;
};

/// Encodes raw estimates (see the header comment).
GradientVolume encode_gradients(const std::vector<Eigen::Vector3f>& g, const std::array<int, 3>& dims,
                                const GradientOptions& options);

/// Estimate and encode. Throws InputError for a radius outside [1, 4] or bits other than 4 and 8.
GradientVolume build_gradient_volume(const Volume& volume, const GradientOptions& options);

/// The cache file name of a volume and options: "<content hash>.grad".
std::string gradient_cache_name(const Volume& volume, const GradientOptions& options);

/// build_gradient_volume through the cache folder `cache_dir` (created if missing): read the file
/// when it exists and is well formed, else compute and write it atomically. An empty cache_dir
/// computes without caching.
GradientVolume cached_gradient_volume(const Volume& volume, const GradientOptions& options,
                                      const std::filesystem::path& cache_dir);

}  // namespace meltlab::render
