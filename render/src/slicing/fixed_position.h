#pragma once
// Sample positions of the slicing renderer's incremental path (SlicingSettings::exact_positions
// false) in index coordinates as 32.32 fixed point: per ray the first visited plane's position g_0
// and the move per plane Δg, each rounded once from the double arithmetic (to the nearest 2⁻³²
// voxel), and sample j at g_0 + j Δg by integer arithmetic. Exact integer sums give every path that
// steps a ray — one ray at a time, the packets' walk by adds, their fetch by a product — the same
// positions bit for bit, and the error against the exact o + t_k v is below (j + 1) 2⁻³³ voxel
// plus the double rounding of g_0 and Δg (1e-7 voxel after 1000 planes; float positions erred
// by up to 2⁻¹⁷ voxel beyond 128).
// The sums are taken modulo 2⁶⁴ (unsigned: defined wrapping), which is exact wherever the true
// value fits, as it does for every sample inside the volume's box: lanes outside their planes
// may wrap, and their values are never used.
// From a position: the voxel floor(g) (the stencil's lower corner) and the trilinear weight
// g - floor(g) as a float, the fraction's top 24 bits (exact in a float; 2⁻²⁴ voxel resolution).

#include "packet.h"

#include <cmath>
#include <cstdint>

namespace meltlab::render::fixed {

constexpr double kOne = 4294967296.0;  ///< 2³² (one voxel)

/// x voxels as fixed point (|x| < 2³⁰; rounded to the nearest, ties to even).
inline std::uint64_t from_double(double x) { return std::uint64_t(std::llrint(x * kOne)); }
inline int floor_voxel(std::uint64_t g) { return int(std::int64_t(g) >> 32); }
inline float weight(std::uint64_t g) { return float(std::int32_t((g & 0xffffffffu) >> 8)) * 0x1p-24f; }
/// g in voxels as a double (exact for |g| < 2²¹ voxels).
inline double to_double(std::uint64_t g) { return double(std::int64_t(g)) * 0x1p-32; }

/// The same per lane.
inline packet::VI floor_voxel(packet::VU g) {
  // The high 32 bits of each 64-bit lane (little endian: 32-bit element 2l + 1), by one permute:
  // the bits of int(std::int64_t(g) >> 32).
  using V32 = std::int32_t __attribute__((vector_size(sizeof(packet::VU))));
  const V32 w = V32(g);
#if MELTLAB_PACKET_LANES == 8
  return __builtin_shufflevector(w, w, 1, 3, 5, 7, 9, 11, 13, 15);
#else
  return __builtin_shufflevector(w, w, 1, 3, 5, 7);
#endif
}
inline packet::VF weight(packet::VU g) {
  // The low 32 bits of each lane (32-bit element 2l) by one permute, then their top 24 bits.
  using U32 = std::uint32_t __attribute__((vector_size(sizeof(packet::VU))));
  using VUI = std::uint32_t __attribute__((vector_size(sizeof(packet::VI))));
  const U32 w = U32(g);
#if MELTLAB_PACKET_LANES == 8
  const VUI low = __builtin_shufflevector(w, w, 0, 2, 4, 6, 8, 10, 12, 14);
#else
  const VUI low = __builtin_shufflevector(w, w, 0, 2, 4, 6);
#endif
  return __builtin_convertvector(packet::VI(low >> 8), packet::VF) * 0x1p-24f;
}
/// g's fraction (g - floor(g)) in units of 2⁻³² voxel, as a double (exact).
inline packet::VD fraction(packet::VU g) { return __builtin_convertvector(g & 0xffffffffu, packet::VD); }

}  // namespace meltlab::render::fixed
