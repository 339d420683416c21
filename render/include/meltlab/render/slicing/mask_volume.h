#pragma once
// Seed 003's mask volume (spec ../shared/spec/volume-slicing-importance.md §2.4): a grid of region
// indices 0-4 at its own resolution (vsi.mask.resolution, default 100³) over the data's box,
// initialised to 1. Index 0 cuts away (α = 0), 1-4 pick one of four transfer functions. Lookup uses
// the data's normalised coordinate u = (x - lo) / L with nearest filtering (vsi.mask.filter): cell
// ⌊u n⌋ clamped to [0, n - 1] (cells are cell-centred: n cells span the box).
//
// Edits write an index into every cell whose centre lies inside a mask object (vsi.mask.object_shape:
// an oriented box, a sphere or an ellipsoid), given in the normalised box coordinates [0, 1]³ (so a
// scene's mask set-up does not depend on the volume's scale): centre c, half sizes (box) or radii
// (ellipsoid; a sphere has one radius), and a rotation R = Rz(γ) Ry(β) Rx(α) from the object's axes
// (rotate_deg: [α, β, γ]); a point u is inside when q = Rᵀ (u - c) has |q_i| <= h_i (box) or
// Σ (q_i / h_i)² <= 1 (ellipsoid, sphere). Later edits overwrite earlier ones.

#include <meltlab/render/volume/volume.h>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace meltlab::render {

enum class MaskShape { kBox, kSphere, kEllipsoid };

struct MaskEdit {
  MaskShape shape = MaskShape::kBox;
  Eigen::Vector3d centre = Eigen::Vector3d::Constant(0.5);      ///< normalised box coordinates
  Eigen::Vector3d half_size = Eigen::Vector3d::Constant(0.25);  ///< box: half sizes; ellipsoid/sphere: radii
  Eigen::Vector3d rotate_deg = Eigen::Vector3d::Zero();         ///< [α, β, γ] about x, y, z
  int index = 0;                                                ///< 0-4
  /// Whether the normalised point u is inside the object.
  bool contains(const Eigen::Vector3d& u) const;
};

std::string mask_shape_name(MaskShape s);

/// MaskVolume::lookup in a volume's index coordinates, as the slicing renderer's samples carry them:
/// the sample at g = i + w (i its trilinear stencil's lower corner, w in [0, 1) its weight; the world
/// point origin + g ∘ spacing) is in cell ⌊(float(i) + w) s_a + o_a⌋ clamped to [0, n_a - 1] per axis,
/// s_a = spacing_a n_a / L_a and o_a = (origin_a - lo_a) n_a / L_a rounded to float (L the mask box's
/// size). In float, where lookup() takes the world point in double: a cell's face moves by about
/// 2⁻²³ (|g_a| s_a + |o_a|) cells (2⁻¹⁶ of a cell for a 256-voxel axis), below anything a region mask
/// of nearest cells resolves, and eight lanes compute the same bits (no division, no double).
struct MaskIndexLookup {
  std::array<float, 3> scale{1, 1, 1}, offset{0, 0, 0};
  std::array<int, 3> n{1, 1, 1};
  const std::uint8_t* cells = nullptr;  ///< x fastest, followed by 3 readable bytes (32-bit gathers)

  /// The cell along axis a of the sample at i + w.
  int axis_cell(int a, int i, float w) const {
    const std::size_t k = std::size_t(a);
    const float f = std::floor((float(i) + w) * scale[k] + offset[k]);
    return f < 0 ? 0 : (f >= float(n[k]) ? n[k] - 1 : int(f));
  }
  /// The index (0-4) at the sample i + wx, j + wy, k + wz.
  int lookup(int i, int j, int k, float wx, float wy, float wz) const {
    const int c0 = axis_cell(0, i, wx), c1 = axis_cell(1, j, wy), c2 = axis_cell(2, k, wz);
    return cells[std::size_t(c0 + n[0] * (c1 + n[1] * c2))];
  }
};

class MaskVolume {
 public:
  MaskVolume() = default;
  /// A mask of nx x ny x nz cells over `box`, every cell `index`. Throws InputError for a
  /// dimension outside [1, 1024] or an index outside [0, 4].
  MaskVolume(const std::array<int, 3>& dims, const Box3& box, int index = 1);

  bool empty() const { return cells_.empty(); }
  std::array<int, 3> dims() const { return n_; }
  const Box3& box() const { return box_; }
  /// The index of cell (i, j, k).
  int at(int i, int j, int k) const {
    return cells_[std::size_t(i) + std::size_t(n_[0]) * (j + std::size_t(n_[1]) * k)];
  }
  /// Nearest lookup at a world point (clamped to the box).
  int lookup(const Eigen::Vector3d& p_world) const {
    int c[3];
    for (int a = 0; a < 3; ++a) {
      const double u = (p_world[a] - box_.lo[a]) * inv_size_[a];
      const double f = std::floor(u * n_[a]);
      c[a] = f < 0 ? 0 : (f >= n_[a] ? n_[a] - 1 : int(f));
    }
    return at(c[0], c[1], c[2]);
  }
  /// The cells (x fastest), followed by 3 padding bytes (MaskIndexLookup's 32-bit gathers).
  const std::uint8_t* cells() const { return cells_.data(); }
  /// lookup() for the samples of a volume with this index origin and spacing (MaskIndexLookup).
  MaskIndexLookup index_lookup(const Eigen::Vector3d& origin, const Eigen::Vector3d& spacing) const;
  /// Writes the edit's index into the cells whose centres are inside it (InputError for an index
  /// outside [0, 4] or a non-positive size); returns the number of cells written.
  std::int64_t apply(const MaskEdit& edit);
  /// Number of cells holding each index 0-4.
  std::array<std::int64_t, 5> histogram() const;

 private:
  std::array<int, 3> n_{0, 0, 0};
  Box3 box_;
  Eigen::Vector3d inv_size_ = Eigen::Vector3d::Ones();
  std::vector<std::uint8_t> cells_;  ///< n_[0] n_[1] n_[2] cells and 3 padding bytes
};

}  // namespace meltlab::render
