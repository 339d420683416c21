// The dense scalar volume (see volume/volume.h).

#include <meltlab/render/volume/volume.h>

#include <meltlab/core/error.h>
#include <meltlab/core/limits.h>

#include "sample_storage.h"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

namespace meltlab::render {

int sample_bytes(SampleType type) {
  switch (type) {
    case SampleType::kUint8:
      return 1;
    case SampleType::kUint16:
      return 2;
    case SampleType::kFloat32:
      break;
  }
  return 4;
}

std::string sample_type_name(SampleType type) {
  switch (type) {
    case SampleType::kUint8:
      return "uint8";
    case SampleType::kUint16:
      return "uint16";
    case SampleType::kFloat32:
      break;
  }
  return "float32";
}

namespace {

double max_stored(SampleType type) {
  switch (type) {
    case SampleType::kUint8:
      return 255.0;
    case SampleType::kUint16:
      return 65535.0;
    case SampleType::kFloat32:
      break;
  }
  return 1.0;
}

}  // namespace

Volume Volume::allocate(int nx, int ny, int nz, SampleType type, const std::string& what) {
  if (nx < 1 || ny < 1 || nz < 1)
    throw InputError(fmt::format("{}: dimensions must be at least 1 (got {} x {} x {})", what, nx, ny, nz));
  const std::int64_t n = checked_mul(checked_mul(nx, ny), nz);
  if (n < 0) throw InputError(fmt::format("{}: {} x {} x {} samples overflow", what, nx, ny, nz));
  check_count(what, "samples", n, input_limits().volume_samples, "volume_samples");
  Volume v;
  void* data = nullptr;
  v.owner_ = detail::zeroed_samples(type, n, data);
  v.data_ = data;
  v.mutable_ = data;
  v.type_ = type;
  v.n_ = {nx, ny, nz};
  v.stride_ = {1, nx, std::int64_t(nx) * ny};
  v.scale_ = 1.0 / max_stored(type);
  return v;
}

Volume Volume::wrap(std::shared_ptr<const void> owner, const void* data, SampleType type, int nx, int ny, int nz,
                    std::int64_t sx, std::int64_t sy, std::int64_t sz) {
  Volume v;
  v.owner_ = std::move(owner);
  v.data_ = data;
  v.type_ = type;
  v.n_ = {nx, ny, nz};
  v.stride_ = {sx, sy, sz};
  v.scale_ = 1.0 / max_stored(type);
  return v;
}

Volume Volume::view_of(const Grid3<float>& grid) {
  Volume v = wrap(std::shared_ptr<const void>(), grid.value.data(), SampleType::kFloat32, grid.nx, grid.ny, grid.nz, 1,
                  grid.nx, std::int64_t(grid.nx) * grid.ny);
  v.placement_ = SamplePlacement::kCellCentred;
  v.spacing_ = Eigen::Vector3d::Constant(grid.h_m);
  v.origin_ = grid.origin_m + 0.5 * v.spacing_;
  return v;
}

bool Volume::x_fastest_packed() const {
  return stride_[0] == 1 && stride_[1] == n_[0] && stride_[2] == std::int64_t(n_[0]) * n_[1];
}

void PlacedGrid::fit_to_box(const Box3& box) {
  const Eigen::Vector3d size = box.size();
  if (!(size.minCoeff() > 0.0) || !size.allFinite())
    throw InputError(
        fmt::format("volume box must have positive, finite sides (got {} x {} x {})", size.x(), size.y(), size.z()));
  for (int a = 0; a < 3; ++a) {
    if (placement_ == SamplePlacement::kCellCentred) {
      spacing_[a] = size[a] / n_[std::size_t(a)];
      origin_[a] = box.lo[a] + 0.5 * spacing_[a];
    } else {
      if (n_[std::size_t(a)] < 2)
        throw InputError("a volume of node samples needs at least 2 samples per axis to span a box");
      spacing_[a] = size[a] / (n_[std::size_t(a)] - 1);
      origin_[a] = box.lo[a];
    }
  }
}

Box3 PlacedGrid::domain() const {
  Box3 b;
  const Eigen::Vector3d n(n_[0], n_[1], n_[2]);
  if (placement_ == SamplePlacement::kCellCentred) {
    b.lo = origin_ - 0.5 * spacing_;
    b.hi = origin_ + (n - Eigen::Vector3d::Constant(0.5)).cwiseProduct(spacing_);
  } else {
    b.lo = origin_;
    b.hi = origin_ + (n - Eigen::Vector3d::Ones()).cwiseProduct(spacing_);
  }
  return b;
}

float Volume::value(int i, int j, int k) const {
  return visit_samples(*this, [&](const auto& s) { return s.at(i, j, k); });
}

void Volume::set_value(int i, int j, int k, double value) {
  if (!mutable_) throw InvariantError("Volume::set_value on a volume that does not own its samples");
  const std::int64_t o = i * stride_[0] + j * stride_[1] + k * stride_[2];
  switch (type_) {
    case SampleType::kFloat32:
      static_cast<float*>(mutable_)[o] = static_cast<float>(value);
      break;
    case SampleType::kUint8:
      static_cast<std::uint8_t*>(mutable_)[o] =
          static_cast<std::uint8_t>(std::lround(std::clamp(value / scale_, 0.0, 255.0)));
      break;
    case SampleType::kUint16:
      static_cast<std::uint16_t*>(mutable_)[o] =
          static_cast<std::uint16_t>(std::lround(std::clamp(value / scale_, 0.0, 65535.0)));
      break;
  }
}

float Volume::sample(const Eigen::Vector3d& p, VolumeAddress address, float outside) const {
  const Box3 d = domain();
  if (!d.contains(p)) return outside;
  const Eigen::Vector3d g = index_from_world(p);
  return visit_samples(*this, [&](const auto& s) {
    return address == VolumeAddress::kWrap ? s.trilinear_wrapped(float(g.x()), float(g.y()), float(g.z()))
                                           : s.trilinear_clamped(float(g.x()), float(g.y()), float(g.z()));
  });
}

Eigen::Vector3d Volume::gradient_index(int i, int j, int k) const {
  auto v = [&](int a, int b, int c) {
    return double(value(std::clamp(a, 0, n_[0] - 1), std::clamp(b, 0, n_[1] - 1), std::clamp(c, 0, n_[2] - 1)));
  };
  return 0.5 * Eigen::Vector3d(v(i + 1, j, k) - v(i - 1, j, k), v(i, j + 1, k) - v(i, j - 1, k),
                               v(i, j, k + 1) - v(i, j, k - 1));
}

Eigen::Vector3d Volume::gradient(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d g = index_from_world(p);
  const Eigen::Vector3d f = g.array().floor();
  const Eigen::Vector3d t = g - f;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int c = 0; c < 8; ++c) {
    const int di = c & 1, dj = (c >> 1) & 1, dk = (c >> 2) & 1;
    const double w = (di ? t.x() : 1 - t.x()) * (dj ? t.y() : 1 - t.y()) * (dk ? t.z() : 1 - t.z());
    if (w == 0.0) continue;
    const int i = std::clamp(int(f.x()) + di, 0, n_[0] - 1), j = std::clamp(int(f.y()) + dj, 0, n_[1] - 1),
              k = std::clamp(int(f.z()) + dk, 0, n_[2] - 1);
    sum += w * gradient_index(i, j, k);
  }
  return sum.cwiseQuotient(spacing_);
}

std::array<float, 2> Volume::value_range() const {
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  visit_samples(*this, [&](const auto& s) {
    for (int k = 0; k < n_[2]; ++k)
      for (int j = 0; j < n_[1]; ++j)
        for (int i = 0; i < n_[0]; ++i) {
          const float x = s.at(i, j, k);
          lo = std::min(lo, x);
          hi = std::max(hi, x);
        }
    return 0;
  });
  return {lo, hi};
}

Volume Volume::to_float32() const {
  Volume out = allocate(n_[0], n_[1], n_[2], SampleType::kFloat32);
  out.place_like(*this);
  out.scale_ = 1.0;
  auto* o = static_cast<float*>(out.mutable_);
  visit_samples(*this, [&](const auto& s) {
    std::int64_t c = 0;
    for (int k = 0; k < n_[2]; ++k)
      for (int j = 0; j < n_[1]; ++j)
        for (int i = 0; i < n_[0]; ++i) o[c++] = s.at(i, j, k);
    return 0;
  });
  return out;
}

Volume Volume::quantised(SampleType type) const {
  Volume out = allocate(n_[0], n_[1], n_[2], type);
  out.origin_ = origin_;
  out.spacing_ = spacing_;
  out.placement_ = placement_;
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j)
      for (int i = 0; i < n_[0]; ++i) out.set_value(i, j, k, std::clamp(double(value(i, j, k)), 0.0, 1.0));
  return out;
}

}  // namespace meltlab::render
