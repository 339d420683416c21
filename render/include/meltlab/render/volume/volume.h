#pragma once
// The dense scalar volume of the volume renderers (seeds 000, 001, 003): nx x ny x nz samples of
// one scalar, stored as float32, uint8 or uint16, placed in the world by an axis-aligned affine
// map, sampled trilinearly with clamp or wrap addressing, with central-difference gradients
// ([3.11] of seed 000).
//
// Frames and units: index space (i, j, k) counts samples; world space is the scene's (scene
// units, e.g. the 300-unit box of seed 000). Sample (i, j, k) sits at
//   world = origin + (i * spacing.x, j * spacing.y, k * spacing.z)
// and `domain()` is the world box the volume is defined on:
//   cell-centred samples (textures, Grid3, seed 000's DDS textures: a box of n cells, one value
//     per cell at its centre): [origin - spacing/2, origin + (n - 1/2) spacing];
//   node samples (seed 001's and 003's voxels: n points span n - 1 spacings): [origin,
//     origin + (n - 1) spacing].
// Values: value = stored * value_scale (1 for float32; 1/255 or 1/65535 when an 8- or 16-bit
// volume quantises values in [0, 1]; 1 when 8-bit samples are raw data such as seed 001's 0..255).
//
// Memory: the samples are held through a shared owner (a vector, a memory-mapped file, or a
// borrowed Grid3 that outlives the volume), with element strides, so a z-fastest file (seed 001)
// is read in place and copies of a Volume share the samples.

#include <meltlab/core/grid3.h>

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace meltlab::render {

/// How a volume stores its samples.
enum class SampleType { kFloat32, kUint8, kUint16 };

/// Bytes per sample of a type.
int sample_bytes(SampleType type);
/// "float32", "uint8", "uint16".
std::string sample_type_name(SampleType type);

/// What a lookup beyond the outermost samples reads (vlr.tex.address).
enum class VolumeAddress {
  kClamp,  ///< the nearest border sample (the harness's default)
  kWrap,   ///< the volume tiles space (the source's sampler state)
};

/// Where the samples sit in the volume's box (see the header comment).
enum class SamplePlacement { kCellCentred, kNodes };

/// An axis-aligned world box.
struct Box3 {
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  Eigen::Vector3d size() const { return hi - lo; }
  Eigen::Vector3d centre() const { return 0.5 * (lo + hi); }
  double diagonal() const { return size().norm(); }
  bool contains(const Eigen::Vector3d& p) const {
    return p.x() >= lo.x() && p.y() >= lo.y() && p.z() >= lo.z() && p.x() <= hi.x() && p.y() <= hi.y() &&
           p.z() <= hi.z();
  }
};

/// The typed view of a volume's samples that the integrators' inner loops use: a pointer, the
/// dimensions and element strides. Trilinear lookups in index coordinates (sample centres at
/// integers) with clamped indices, arithmetic in float.
template <class T>
struct VolumeSamples {
  const T* data = nullptr;
  int nx = 0, ny = 0, nz = 0;
  std::int64_t sx = 1, sy = 0, sz = 0;  ///< element strides
  float scale = 1.0f;                   ///< value = stored * scale

  float at(int i, int j, int k) const { return static_cast<float>(data[i * sx + j * sy + k * sz]) * scale; }
  /// Trilinear value at index coordinates (gx, gy, gz), indices clamped to the volume (clamp
  /// addressing). The arithmetic order is fixed (x, then y, then z), so every caller that samples
  /// the same point gets the same bits.
  float trilinear_clamped(float gx, float gy, float gz) const {
    const float fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
    return trilinear_cell(static_cast<int>(fx), static_cast<int>(fy), static_cast<int>(fz), gx - fx, gy - fy, gz - fz);
  }
  /// The same with the lower corner (i0, j0, k0) of the stencil and the weights given (clamped
  /// indices): for callers that located the point already.
  [[gnu::always_inline]] float trilinear_cell(int i0, int j0, int k0, float tx, float ty, float tz) const {
    const std::int64_t x0 = clampi(i0, nx) * sx, x1 = clampi(i0 + 1, nx) * sx;
    const std::int64_t y0 = clampi(j0, ny) * sy, y1 = clampi(j0 + 1, ny) * sy;
    const std::int64_t z0 = clampi(k0, nz) * sz, z1 = clampi(k0 + 1, nz) * sz;
    return blend(x0, x1, y0, y1, z0, z1, tx, ty, tz);
  }
  /// Trilinear value with wrapped indices (the volume repeats with period n along each axis).
  float trilinear_wrapped(float gx, float gy, float gz) const {
    const float fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
    const float tx = gx - fx, ty = gy - fy, tz = gz - fz;
    const std::int64_t i0 = wrapi(static_cast<std::int64_t>(fx), nx), j0 = wrapi(static_cast<std::int64_t>(fy), ny),
                       k0 = wrapi(static_cast<std::int64_t>(fz), nz);
    const std::int64_t x0 = i0 * sx, x1 = (i0 + 1 == nx ? 0 : i0 + 1) * sx;
    const std::int64_t y0 = j0 * sy, y1 = (j0 + 1 == ny ? 0 : j0 + 1) * sy;
    const std::int64_t z0 = k0 * sz, z1 = (k0 + 1 == nz ? 0 : k0 + 1) * sz;
    return blend(x0, x1, y0, y1, z0, z1, tx, ty, tz);
  }

 private:
  [[gnu::always_inline]] static std::int64_t clampi(int i, int n) { return i < 0 ? 0 : (i >= n ? n - 1 : i); }
  static std::int64_t wrapi(std::int64_t i, int n) {
    const std::int64_t r = i % n;
    return r < 0 ? r + n : r;
  }
  [[gnu::always_inline]] float blend(std::int64_t x0, std::int64_t x1, std::int64_t y0, std::int64_t y1,
                                     std::int64_t z0, std::int64_t z1, float tx, float ty, float tz) const {
    auto v = [this](std::int64_t o) { return static_cast<float>(data[o]); };
    const float c00 = v(x0 + y0 + z0) * (1 - tx) + v(x1 + y0 + z0) * tx;
    const float c10 = v(x0 + y1 + z0) * (1 - tx) + v(x1 + y1 + z0) * tx;
    const float c01 = v(x0 + y0 + z1) * (1 - tx) + v(x1 + y0 + z1) * tx;
    const float c11 = v(x0 + y1 + z1) * (1 - tx) + v(x1 + y1 + z1) * tx;
    return ((c00 * (1 - ty) + c10 * ty) * (1 - tz) + (c01 * (1 - ty) + c11 * ty) * tz) * scale;
  }
};

/// What the dense Volume and the BrickedVolume (bricked_volume.h) share: samples of one type held
/// through a shared owner, the count per axis, the placement in the world (origin, spacing, cell-
/// centred or node samples; see the header comment) and the value scale. Not used on its own.
class PlacedGrid {
 public:
  bool empty() const { return data_ == nullptr; }
  SampleType type() const { return type_; }
  int nx() const { return n_[0]; }
  int ny() const { return n_[1]; }
  int nz() const { return n_[2]; }
  std::array<int, 3> dims() const { return n_; }
  std::int64_t sample_count() const { return std::int64_t(n_[0]) * n_[1] * n_[2]; }
  /// Raw pointer to the samples (of the stored type, in the grid's layout).
  const void* data() const { return data_; }
  /// Writable samples of a grid that owns them (allocate()); nullptr otherwise.
  void* mutable_data() const { return mutable_; }

  // --- placement in the world ---
  Eigen::Vector3d origin() const { return origin_; }
  Eigen::Vector3d spacing() const { return spacing_; }
  SamplePlacement placement() const { return placement_; }
  void set_placement(SamplePlacement p) { placement_ = p; }
  void set_origin(const Eigen::Vector3d& o) { origin_ = o; }
  void set_spacing(const Eigen::Vector3d& s) { spacing_ = s; }
  /// Places the grid so that its domain is `box` (origin and spacing from the box and the
  /// placement). Throws InputError for an empty box or a node grid with a dimension of 1.
  void fit_to_box(const Box3& box);
  Box3 domain() const;
  /// Index coordinates of a world point (sample centres at integers).
  Eigen::Vector3d index_from_world(const Eigen::Vector3d& p_world) const {
    return (p_world - origin_).cwiseQuotient(spacing_);
  }
  Eigen::Vector3d world_from_index(const Eigen::Vector3d& g) const { return origin_ + g.cwiseProduct(spacing_); }

  // --- values ---
  double value_scale() const { return scale_; }
  void set_value_scale(double s) { scale_ = s; }
  /// Takes origin, spacing, placement and value scale from `other` (a copy in another layout).
  void place_like(const PlacedGrid& other) {
    origin_ = other.origin_;
    spacing_ = other.spacing_;
    placement_ = other.placement_;
    scale_ = other.scale_;
  }

 protected:
  PlacedGrid(SampleType type, SamplePlacement placement) : type_(type), placement_(placement) {}

  std::shared_ptr<const void> owner_;
  const void* data_ = nullptr;
  void* mutable_ = nullptr;
  SampleType type_;
  std::array<int, 3> n_{0, 0, 0};
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero(), spacing_ = Eigen::Vector3d::Ones();
  SamplePlacement placement_;
  double scale_ = 1.0;
};

/// A dense scalar volume (see the header comment). Cheap to copy: copies share the samples.
class Volume : public PlacedGrid {
 public:
  Volume() : PlacedGrid(SampleType::kFloat32, SamplePlacement::kCellCentred) {}

  /// A new volume of zeros, x fastest, owning its samples. Throws InputError for dimensions
  /// < 1 or a sample count over input_limits().volume_samples (`what` names it in the message).
  static Volume allocate(int nx, int ny, int nz, SampleType type, const std::string& what = "volume");
  /// A volume over samples owned elsewhere: `owner` keeps `data` alive; strides in elements.
  static Volume wrap(std::shared_ptr<const void> owner, const void* data, SampleType type, int nx, int ny, int nz,
                     std::int64_t sx, std::int64_t sy, std::int64_t sz);
  /// A cell-centred float view of a Grid3 (no copy; the grid must outlive the volume and every
  /// copy of it): origin at the centre of cell (0, 0, 0), spacing h.
  static Volume view_of(const Grid3<float>& grid);

  std::array<std::int64_t, 3> strides() const { return stride_; }
  /// True when x is fastest and rows/slices are packed (stride 1, nx, nx*ny).
  bool x_fastest_packed() const;

  /// The value of sample (i, j, k) (inside the volume).
  float value(int i, int j, int k) const;
  /// Sets the stored sample from a value: float32 stores it, 8/16-bit store
  /// round(clamp(value / value_scale, 0, max)). Only for volumes that own their samples.
  void set_value(int i, int j, int k, double value);
  /// Trilinear value at a world point; `outside` beyond the domain.
  float sample(const Eigen::Vector3d& p_world, VolumeAddress address = VolumeAddress::kClamp,
               float outside = 0.0f) const;
  /// Central differences [3.11] at sample (i, j, k) with clamp-to-edge neighbours, in value per
  /// index unit (the source's raw differences: vlr.gradient.scale = raw).
  Eigen::Vector3d gradient_index(int i, int j, int k) const;
  /// The world-space gradient at a world point: trilinear interpolation of the sample gradients,
  /// divided by the spacing (value per scene unit).
  Eigen::Vector3d gradient(const Eigen::Vector3d& p_world) const;
  /// Minimum and maximum value.
  std::array<float, 2> value_range() const;

  /// The typed view for inner loops; T must be the stored type.
  template <class T>
  VolumeSamples<T> samples() const {
    VolumeSamples<T> s;
    s.data = static_cast<const T*>(data_);
    s.nx = n_[0];
    s.ny = n_[1];
    s.nz = n_[2];
    s.sx = stride_[0];
    s.sy = stride_[1];
    s.sz = stride_[2];
    s.scale = static_cast<float>(scale_);
    return s;
  }

  /// A float32 copy, x fastest (values, not stored numbers: scale 1), same placement.
  Volume to_float32() const;
  /// A copy quantised to 8 or 16 bits: stored = round(clamp(value, 0, 1) * max), scale 1/max.
  Volume quantised(SampleType type) const;

 private:
  std::array<std::int64_t, 3> stride_{1, 0, 0};
};

/// Calls fn(samples) with the typed view of a volume's stored type (one dispatch per call,
/// outside any inner loop): a Volume, or any volume type with type() and samples<T>()
/// (BrickedVolume).
template <class V, class Fn>
requires requires(const V& v) {
  v.type();
  v.template samples<float>();
}
decltype(auto) visit_samples(const V& v, Fn&& fn) {
  switch (v.type()) {
    case SampleType::kUint8:
      return fn(v.template samples<std::uint8_t>());
    case SampleType::kUint16:
      return fn(v.template samples<std::uint16_t>());
    case SampleType::kFloat32:
      break;
  }
  return fn(v.template samples<float>());
}

}  // namespace meltlab::render
