// Seed 001's blocked layout (see volume/bricked_volume.h).

#include <meltlab/render/volume/bricked_volume.h>

#include <meltlab/core/error.h>
#include <meltlab/core/limits.h>

#include "sample_storage.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <vector>

namespace meltlab::render {

int BrickedVolume::blocks_per_axis(int n, int side) { return std::max(1, (n - 1 + side - 2) / (side - 1)); }

std::int64_t BrickedVolume::stored_samples(const std::array<int, 3>& dims, int side) {
  if (side < 2) return -1;
  const std::int64_t b3 = std::int64_t(side) * side * side;
  std::int64_t blocks = 1;
  for (int a = 0; a < 3; ++a) blocks = checked_mul(blocks, blocks_per_axis(dims[std::size_t(a)], side));
  return blocks < 0 ? -1 : checked_mul(blocks, b3);
}

BrickedVolume BrickedVolume::allocate(const std::array<int, 3>& dims, int side, SampleType type,
                                      const std::string& what) {
  for (int d : dims)
    if (d < 2)
      throw InputError(fmt::format("{}: a volume of node samples needs at least 2 voxels per axis (got {} x {} x {})",
                                   what, dims[0], dims[1], dims[2]));
  if (side < 2 || side > 255)
    throw InputError(fmt::format("{}: the block side must be in [2, 255] (got {})", what, side));
  const std::int64_t voxels = checked_mul(checked_mul(dims[0], dims[1]), dims[2]);
  check_count(what, "voxels", voxels, input_limits().volume_samples, "volume_samples");
  const std::int64_t stored = stored_samples(dims, side);
  if (stored < 0) throw InputError(fmt::format("{}: the blocked layout's sample count overflows", what));
  void* data = nullptr;
  const std::shared_ptr<void> owner = detail::zeroed_samples(type, stored, data);
  BrickedVolume v = wrap(owner, data, type, dims, side);
  v.mutable_ = data;
  return v;
}

BrickedVolume BrickedVolume::wrap(std::shared_ptr<const void> owner, const void* data, SampleType type,
                                  const std::array<int, 3>& dims, int side) {
  BrickedVolume v;
  v.owner_ = std::move(owner);
  v.data_ = data;
  v.type_ = type;
  v.n_ = dims;
  v.side_ = side;
  for (int a = 0; a < 3; ++a) v.nb_[std::size_t(a)] = blocks_per_axis(dims[std::size_t(a)], side);
  v.scale_ = 1.0;
  return v;
}

std::array<int, 3> BrickedVolume::block_hi(int bx, int by, int bz) const {
  const int b[3] = {bx, by, bz};
  std::array<int, 3> hi{};
  for (int a = 0; a < 3; ++a) hi[std::size_t(a)] = std::min(n_[std::size_t(a)] - 1, b[a] * (side_ - 1) + side_ - 1);
  return hi;
}

BrickedVolume BrickedVolume::from_volume(const Volume& src, int side) {
  BrickedVolume out = allocate(src.dims(), side, src.type(), "bricked volume");
  out.place_like(src);
  const int B = side;
  visit_samples(src, [&](const auto& s) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(s.data)>>;
    T* dst = static_cast<T*>(out.mutable_);
    const std::int64_t b3 = std::int64_t(B) * B * B;
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, out.block_count()), [&](const auto& r) {
      for (std::int64_t b = r.begin(); b < r.end(); ++b) {
        const int bz = int(b % out.nb_[2]), by = int((b / out.nb_[2]) % out.nb_[1]),
                  bx = int(b / out.nb_[2] / out.nb_[1]);
        T* block = dst + b * b3;
        for (int lx = 0; lx < B; ++lx)
          for (int ly = 0; ly < B; ++ly)
            for (int lz = 0; lz < B; ++lz) {
              const int i = bx * (B - 1) + lx, j = by * (B - 1) + ly, k = bz * (B - 1) + lz;
              if (i < s.nx && j < s.ny && k < s.nz)  // else the zero padding
                block[(std::int64_t(lx) * B + ly) * B + lz] = s.data[i * s.sx + j * s.sy + k * s.sz];
            }
      }
    });
    return 0;
  });
  return out;
}

Volume BrickedVolume::to_volume() const {
  Volume v = Volume::allocate(n_[0], n_[1], n_[2], type_, "volume");
  v.place_like(*this);
  visit_samples(*this, [&](const auto& s) {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(s.data)>>;
    T* dst = static_cast<T*>(v.mutable_data());
    tbb::parallel_for(0, n_[2], [&](int k) {
      for (int j = 0; j < n_[1]; ++j)
        for (int i = 0; i < n_[0]; ++i)
          dst[i + std::int64_t(n_[0]) * (j + std::int64_t(n_[1]) * k)] = s.stored(i, j, k);
    });
    return 0;
  });
  return v;
}

BrickedVolume BrickedVolume::to_float32() const {
  BrickedVolume out = allocate(n_, side_, SampleType::kFloat32, "bricked volume");
  out.place_like(*this);
  out.scale_ = 1.0;
  auto* dst = static_cast<float*>(out.mutable_);
  visit_samples(*this, [&](const auto& s) {
    const std::int64_t n = stored_count();
    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, n, 1 << 16), [&](const auto& r) {
      for (std::int64_t i = r.begin(); i < r.end(); ++i) dst[i] = static_cast<float>(s.data[i]) * s.scale;
    });
    return 0;
  });
  return out;
}

float BrickedVolume::value(int i, int j, int k) const {
  return visit_samples(*this, [&](const auto& s) { return s.at(i, j, k); });
}

}  // namespace meltlab::render
