#pragma once
// Private to render/src/volume: the zeroed sample array that Volume::allocate and
// BrickedVolume::allocate own.

#include <meltlab/render/volume/volume.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace meltlab::render::detail {

/// n zeroed samples of `type`; `data` points at the first. The returned pointer owns them.
inline std::shared_ptr<void> zeroed_samples(SampleType type, std::int64_t n, void*& data) {
  auto make = [&]<class T>(T) {
    auto v = std::make_shared<std::vector<T>>(static_cast<std::size_t>(n), T{});
    data = v->data();
    return std::shared_ptr<void>(v);
  };
  switch (type) {
    case SampleType::kUint8:
      return make(std::uint8_t{});
    case SampleType::kUint16:
      return make(std::uint16_t{});
    case SampleType::kFloat32:
      break;
  }
  return make(float{});
}

}  // namespace meltlab::render::detail
