#pragma once
// Seed 001's synthetic volumes (spec ../shared/spec/cpu-large-volumes.md §2.9, §3), as "sample
// generators" for the streamed .clv writer (clv_file.h) and for volumes in memory (generate.h):
//
// ShapesVolume — K random cuboids and spheres (the repo's "shapes" generator):
//   each shape is a cuboid or a sphere with probability 1/2; its size per axis uniform on the
//   integers [s - floor(s/3), s + floor(s/3)] (s the object size); its lower corner uniform such
//   that it fits; its value uniform on [v0 - 10, v0 + 10]; a sphere has radius (x extent)/2,
//   centred in its box. A voxel p takes the value of the first shape in list order whose box
//   contains it (lo <= p < lo + size); if that shape is a sphere and p lies outside the ball
//   (|p - centre| > radius), the voxel is 0 and later shapes are not consulted. Background 0.
//   RNG (clv.gen.rng): xoshiro256** seeded through splitmix64 from a 64-bit seed; the source used
//   fastrand, so the volumes match the source's in distribution, not bit for bit.
//
// SkullPhantom — a CT-like 8-bit head for Table 5.1 (the source's 68 x 256 x 256 volume is not
// identified): an ellipsoidal head cut to a slab of slices — air with noise (0-12), scalp (~25),
// a three-layer skull (outer and inner tables ~200, diploë ~120), brain (~30), two ventricles
// (~12), two eye orbits and a sinus cut through the frontal bone. Under the skull TF (α = 1 on
// (40, 240)) only bone is visible, and it is opaque.

#include <meltlab/render/volume/clv_file.h>

#include <array>
#include <cstdint>
#include <vector>

namespace meltlab::render {

struct ShapesOptions {
  std::array<int, 3> dims{800, 800, 800};
  int count = 70;          ///< K
  int sample = 100;        ///< v0: values on [v0 - 10, v0 + 10]
  int object_size = 70;    ///< s
  std::uint64_t seed = 2;  ///< clv.gen.seed (the spec's seed 2)
};

struct Shape {
  bool sphere = false;
  std::array<int, 3> lo{0, 0, 0}, size{0, 0, 0};
  std::uint8_t value = 0;
};

class ShapesVolume final : public VoxelSource {
 public:
  /// Draws the shapes. Throws InputError for a count < 0, an object size < 1 or one whose largest
  /// shape (s + floor(s/3)) does not fit the volume, or a sample outside [10, 245].
  explicit ShapesVolume(const ShapesOptions& options);
  const ShapesOptions& options() const { return o_; }
  const std::vector<Shape>& shapes() const { return shapes_; }
  std::uint8_t value(int x, int y, int z) const override;
  /// Culls the shapes to those meeting the batch's bounding box, then the rule above per voxel.
  void fill(const VoxelCoord* coords, std::size_t n, std::uint8_t* out) const override;

 private:
  static std::uint8_t value_of(const Shape& s, int x, int y, int z);
  ShapesOptions o_;
  std::vector<Shape> shapes_;
};

class SkullPhantom final : public VoxelSource {
 public:
  /// dims: the slab (default 256 x 256 x 68: 68 slices of 256²); seed: the noise.
  explicit SkullPhantom(const std::array<int, 3>& dims = {256, 256, 68}, std::uint64_t seed = 1);
  std::uint8_t value(int x, int y, int z) const override;

 private:
  std::array<int, 3> n_;
  std::uint64_t seed_;
};

/// The 64-bit generator of the shapes (exposed for the tests of its distribution).
class Xoshiro256 {
 public:
  explicit Xoshiro256(std::uint64_t seed);
  std::uint64_t next();
  /// Uniform on the integers [lo, hi] (unbiased: rejection of the short last interval).
  std::int64_t uniform(std::int64_t lo, std::int64_t hi);

 private:
  std::uint64_t s_[4];
};

}  // namespace meltlab::render
