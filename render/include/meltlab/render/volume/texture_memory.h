#pragma once
// The memory of seed 003's GPU textures (spec volume-slicing-importance.md §2.3, source §5.3.1):
// data GL_ALPHA16 (16 bits per voxel), normals GL_RGB8 (24), mask GL_ALPHA4 (4), render targets
// GL_RGBA16F (64 bits per pixel). The source's example (data and normals 250 x 250 x 150, mask
// 100³) prints the mask as 5 000 000 B; 10⁶ voxels × 4 bits is 500 000 B (vsi.errata.mask_bytes),
// and the printed total 47 375 000 B (45.2 MiB) is the sum with 500 000 B.
// The CPU harness keeps float32 volumes (vsi.data.internal_bits); this is the arithmetic of the
// source's formats, to state the memory a GPU realisation would need.

#include <array>
#include <cstdint>

namespace meltlab::render {

/// Bits per voxel (or pixel) of the source's texture formats.
struct SlicingTextureFormats {
  int data_bits = 16;           ///< GL_ALPHA16 (GL_ALPHA8 fallback: 8)
  int normal_bits = 24;         ///< GL_RGB8 (RGBA4, rejected for banding: 16; RGBA8: 32)
  int mask_bits = 4;            ///< GL_ALPHA4
  int render_target_bits = 64;  ///< GL_RGBA16F_ARB
};

struct SlicingTextureBytes {
  std::int64_t data = 0, normals = 0, mask = 0;
  std::int64_t volumes() const { return data + normals + mask; }  ///< the source's "total"
};

/// ceil(voxels × bits / 8) for each volume (the normals at the data's dimensions).
SlicingTextureBytes slicing_texture_bytes(const std::array<int, 3>& data_dims, const std::array<int, 3>& mask_dims,
                                          const SlicingTextureFormats& formats = {});

/// Bytes of `count` render targets of width × height.
std::int64_t render_target_bytes(int width, int height, int count, const SlicingTextureFormats& formats = {});

}  // namespace meltlab::render
