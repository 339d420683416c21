// The memory of seed 003's GPU textures (see volume/texture_memory.h).

#include <meltlab/render/volume/texture_memory.h>

namespace meltlab::render {

namespace {

std::int64_t bytes_of(const std::array<int, 3>& dims, int bits) {
  const std::int64_t bit_count = std::int64_t(dims[0]) * dims[1] * dims[2] * bits;
  return (bit_count + 7) / 8;
}

}  // namespace

SlicingTextureBytes slicing_texture_bytes(const std::array<int, 3>& data_dims, const std::array<int, 3>& mask_dims,
                                          const SlicingTextureFormats& f) {
  SlicingTextureBytes b;
  b.data = bytes_of(data_dims, f.data_bits);
  b.normals = bytes_of(data_dims, f.normal_bits);
  b.mask = bytes_of(mask_dims, f.mask_bits);
  return b;
}

std::int64_t render_target_bytes(int width, int height, int count, const SlicingTextureFormats& f) {
  return bytes_of({width, height, count}, f.render_target_bits);
}

}  // namespace meltlab::render
