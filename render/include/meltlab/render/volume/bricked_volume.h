#pragma once
// Seed 001's blocked ("bricked") layout (spec ../shared/spec/cpu-large-volumes.md §2.1): cubic
// blocks of B voxels per side whose neighbours share one voxel plane, so that every trilinear cell
// (the 2 x 2 x 2 voxels around a sample) lies inside one block and a block can be rendered alone.
//
//   stride B - 1 (clv.layout.block_overlap = 1); blocks per axis n_b = ceil((N - 1)/(B - 1));
//   voxel x belongs to block min(floor(x / (B - 1)), n_b - 1) at local offset x - (B - 1) · block;
//   each block is B³ samples, z fastest inside; blocks follow one another with the block index z
//   fastest (the repo); voxels of edge blocks beyond the volume are 0 (clv.layout.block_pad_value).
//   Stored samples: n_b,x · n_b,y · n_b,z · B³ (e.g. 54³ · 16³ = 644 972 544 for 800³ in 16³).
//
// Like Volume (volume.h): samples held through a shared owner (a vector or a memory-mapped file),
// placed in the world by an origin and a spacing; seed 001's volumes are node samples (an N-point
// axis spans N - 1 units) with unit spacing and raw values (value_scale 1). Cheap to copy.

#include <meltlab/render/volume/volume.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <string>

namespace meltlab::render {

/// The typed view of a bricked volume's samples for inner loops.
template <class T>
struct BrickSamples {
  const T* data = nullptr;
  int n[3] = {0, 0, 0};          ///< voxels per axis
  int nb[3] = {0, 0, 0};         ///< blocks per axis
  int side = 0;                  ///< B
  int stride = 0;                ///< B - 1
  std::int64_t block_elems = 0;  ///< B³
  float scale = 1.0f;

  /// The first sample of block (bx, by, bz).
  const T* block(int bx, int by, int bz) const {
    return data + ((std::int64_t(bx) * nb[1] + by) * nb[2] + bz) * block_elems;
  }
  /// Offset of local voxel (lx, ly, lz) inside a block (z fastest).
  std::int64_t local(int lx, int ly, int lz) const { return (std::int64_t(lx) * side + ly) * side + lz; }
  /// The block holding voxel i on one axis (a voxel on a shared plane: the later block).
  int block_of(int i, int axis) const { return std::min(i / stride, nb[axis] - 1); }
  /// The stored number of voxel (i, j, k) (inside the volume).
  T stored(int i, int j, int k) const {
    const int bx = block_of(i, 0), by = block_of(j, 1), bz = block_of(k, 2);
    return block(bx, by, bz)[local(i - bx * stride, j - by * stride, k - bz * stride)];
  }
  /// The stored number of voxel (i, j, k), times the scale.
  float at(int i, int j, int k) const { return static_cast<float>(stored(i, j, k)) * scale; }
};

class BrickedVolume : public PlacedGrid {
 public:
  BrickedVolume() : PlacedGrid(SampleType::kUint8, SamplePlacement::kNodes) {}

  /// Blocks per axis for N voxels and block side B: ceil((N - 1)/(B - 1)) (at least 1).
  static int blocks_per_axis(int n, int side);
  /// Stored samples of the layout: n_b,x n_b,y n_b,z B³; -1 if it overflows int64.
  static std::int64_t stored_samples(const std::array<int, 3>& dims, int side);

  /// A zero volume owning its samples. Throws InputError (naming `what`) for dimensions < 2, a side
  /// outside [2, 255], or more voxels than input_limits().volume_samples.
  static BrickedVolume allocate(const std::array<int, 3>& dims, int side, SampleType type,
                                const std::string& what = "bricked volume");
  /// A view of samples owned elsewhere (`owner` keeps `data` alive), in the layout above.
  static BrickedVolume wrap(std::shared_ptr<const void> owner, const void* data, SampleType type,
                            const std::array<int, 3>& dims, int side);
  /// The bricked copy of a (dense) volume: stored numbers, placement and scale kept.
  static BrickedVolume from_volume(const Volume& volume, int side);
  /// The dense copy (x fastest), for tests and tools.
  Volume to_volume() const;
  /// A float32 copy (values, scale 1): seed 001's "float" variant (4x the memory).
  BrickedVolume to_float32() const;

  int side() const { return side_; }
  std::array<int, 3> blocks() const { return nb_; }
  std::int64_t block_count() const { return std::int64_t(nb_[0]) * nb_[1] * nb_[2]; }
  std::int64_t stored_count() const { return block_count() * side_ * side_ * side_; }

  /// The voxels block (bx, by, bz) stores, clipped to the volume: [lo, hi] per axis (inclusive).
  std::array<int, 3> block_lo(int bx, int by, int bz) const {
    return {bx * (side_ - 1), by * (side_ - 1), bz * (side_ - 1)};
  }
  std::array<int, 3> block_hi(int bx, int by, int bz) const;

  /// The value of voxel (i, j, k).
  float value(int i, int j, int k) const;

  template <class T>
  BrickSamples<T> samples() const {
    BrickSamples<T> s;
    s.data = static_cast<const T*>(data_);
    for (int a = 0; a < 3; ++a) s.n[a] = n_[a], s.nb[a] = nb_[a];
    s.side = side_;
    s.stride = side_ - 1;
    s.block_elems = std::int64_t(side_) * side_ * side_;
    s.scale = static_cast<float>(scale_);
    return s;
  }

 private:
  std::array<int, 3> nb_{0, 0, 0};
  int side_ = 0;
};

}  // namespace meltlab::render
