// Seed 003's mask volume (see slicing/mask_volume.h).

#include <meltlab/render/slicing/mask_volume.h>

#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <cmath>

namespace meltlab::render {

namespace {

constexpr std::size_t kPadding = 3;  // MaskVolume::cells()'s bytes after the last cell

Eigen::Matrix3d rotation(const Eigen::Vector3d& deg) {
  const Eigen::Vector3d r = deg * (M_PI / 180.0);
  return (Eigen::AngleAxisd(r.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(r.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace

std::string mask_shape_name(MaskShape s) {
  return s == MaskShape::kBox ? "box" : s == MaskShape::kSphere ? "sphere" : "ellipsoid";
}

bool MaskEdit::contains(const Eigen::Vector3d& u) const {
  const Eigen::Vector3d q = rotation(rotate_deg).transpose() * (u - centre);
  if (shape == MaskShape::kBox) return (q.cwiseAbs().array() <= half_size.array()).all();
  return q.cwiseQuotient(half_size).squaredNorm() <= 1.0;
}

MaskVolume::MaskVolume(const std::array<int, 3>& dims, const Box3& box, int index) : n_(dims), box_(box) {
  for (int a = 0; a < 3; ++a)
    if (dims[std::size_t(a)] < 1 || dims[std::size_t(a)] > 1024)
      throw InputError(fmt::format("slicing: the mask resolution must be in [1, 1024] per axis (got {} x {} x {})",
                                   dims[0], dims[1], dims[2]));
  if (index < 0 || index > 4) throw InputError(fmt::format("slicing: a mask index is 0-4 (got {})", index));
  if (!(box.size().minCoeff() > 0)) throw InputError("slicing: the mask's box is empty");
  inv_size_ = box.size().cwiseInverse();
  cells_.assign(std::size_t(dims[0]) * dims[1] * dims[2] + kPadding, std::uint8_t(index));
}

MaskIndexLookup MaskVolume::index_lookup(const Eigen::Vector3d& origin, const Eigen::Vector3d& spacing) const {
  MaskIndexLookup m;
  for (int a = 0; a < 3; ++a) {
    const double cells_per_unit = n_[std::size_t(a)] * inv_size_[a];
    m.scale[std::size_t(a)] = float(spacing[a] * cells_per_unit);
    m.offset[std::size_t(a)] = float((origin[a] - box_.lo[a]) * cells_per_unit);
  }
  m.n = n_;
  m.cells = cells_.data();
  return m;
}

std::int64_t MaskVolume::apply(const MaskEdit& e) {
  if (e.index < 0 || e.index > 4) throw InputError(fmt::format("slicing: a mask index is 0-4 (got {})", e.index));
  if (!(e.half_size.minCoeff() > 0) || !e.half_size.allFinite() || !e.centre.allFinite() || !e.rotate_deg.allFinite())
    throw InputError("slicing: a mask object needs a finite centre and rotation and sizes > 0");
  // The same rotation for every cell (contains() rebuilds it; hoisted here for speed).
  const Eigen::Matrix3d Rt = rotation(e.rotate_deg).transpose();
  std::int64_t written = 0;
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i) {
        const Eigen::Vector3d u((i + 0.5) / n_[0], (j + 0.5) / n_[1], (k + 0.5) / n_[2]);
        const Eigen::Vector3d q = Rt * (u - e.centre);
        const bool in = e.shape == MaskShape::kBox ? (q.cwiseAbs().array() <= e.half_size.array()).all()
                                                   : q.cwiseQuotient(e.half_size).squaredNorm() <= 1.0;
        if (in) {
          cells_[std::size_t(i) + std::size_t(n_[0]) * (j + std::size_t(n_[1]) * k)] = std::uint8_t(e.index);
          ++written;
        }
      }
  return written;
}

std::array<std::int64_t, 5> MaskVolume::histogram() const {
  std::array<std::int64_t, 5> h{0, 0, 0, 0, 0};
  for (std::size_t i = 0; i + kPadding < cells_.size(); ++i) ++h[cells_[i]];
  return h;
}

}  // namespace meltlab::render
