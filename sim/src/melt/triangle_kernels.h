#pragma once
// Private to the melt cycle: the per-triangle arithmetic of Alg. 1, computed eight triangles
// at a time in SIMD lanes (lanes.h): each group's corners are read from a packed copy of the
// position columns and turned into x, y, z lanes in registers, and the lane arithmetic is the
// scalar formulas' operations in their order (sqrt and division are exactly rounded in SIMD
// too, and contraction is off, so every lane's result is the scalar evaluation's). Serial and
// parallel execution call the same kernel, so their results are bitwise identical.

#include "lanes.h"

#include <meltlab/sim/mesh.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <cstddef>
#include <cstring>
#include <vector>

namespace meltlab::sim {

inline constexpr std::size_t kTriangleBlock = 64;

/// Unit face normal and the three unit edge vectors (a->b, b->c, c->a) of a block, and the
/// squared length of each triangle's shortest edge as a float no greater than it (for the
/// short-edge test's skip: exact for float meshes, rounded down for double ones; +inf for a
/// dead slot).
template <class Real>
struct TriangleBlockTerms {
  Real nx[kTriangleBlock], ny[kTriangleBlock], nz[kTriangleBlock];
  Real ex[3][kTriangleBlock], ey[3][kTriangleBlock], ez[3][kTriangleBlock];
  float min_edge2[kTriangleBlock];
};

// A float no greater than x >= 0 (x itself for a float). For a double, x (1 - 2^-23) rounded to
// the nearest float lies below x by at least 2^-24 of it, more than the rounding to float adds
// (at most 2^-24 relative, for results of normal float size; below that the test that uses the
// key does not rely on it, see mark_short_edges()). Above float's range the IEEE 754 conversion
// gives +inf, a key that skips the triangle: right, as its shortest edge is then longer than any
// reach the test accepts. (A clamp to the largest float stopped GCC 12 vectorising the terms
// loop for double: 1.4-1.7x slower cycles, measured, when that loop was left to GCC's
// vectoriser.)
inline constexpr double kFloatKeyScale = 1.0 - 0x1p-23;
template <class Real>
inline float float_at_most(Real x) {
  static_assert(std::numeric_limits<float>::is_iec559 && std::numeric_limits<double>::is_iec559);
  if constexpr (std::is_same_v<Real, float>)
    return x;
  else
    return static_cast<float>(x * kFloatKeyScale);
}

/// float_at_most() lane by lane.
template <class Real>
inline Lanes<float> lane_float_at_most(const Lanes<Real>& x) {
  if constexpr (std::is_same_v<Real, float>)
    return x;
  else
    return lanes_to_float(x * kFloatKeyScale);
}

/// Copies the position columns of `m` into `out` as packed triples (x, y, z of vertex v at
/// out[3v], out[3v + 1], out[3v + 2]) followed by one padding number, so that every vertex's
/// triple can be read as four numbers (the next vertex's x, or the padding, as the fourth).
template <class Real>
inline void pack_positions(const TriMesh<Real>& m, std::vector<Real>& out) {
  const std::size_t n = m.vertex_slots();
  out.resize(3 * n + 1);
  const Real* X = m.position.x().data();
  const Real* Y = m.position.y().data();
  const Real* Z = m.position.z().data();
  Real* o = out.data();
  for (std::size_t v = 0; v < n; ++v) {
    o[3 * v] = X[v];
    o[3 * v + 1] = Y[v];
    o[3 * v + 2] = Z[v];
  }
  o[3 * n] = Real(0);
}

/// Triangles [first, first + count) of `m`, with corner positions read from `packed` (the
/// positions of `m` as pack_positions() lays them out). A dead slot reads vertex 0 at all
/// three corners: a point, whose normal and edges lane_inverse_length() turns into zero terms.
/// Written eight triangles at a time in lanes rather than as loops over arrays: GCC 12
/// vectorised such loops for AVX-512 but not for AVX2 (-march=x86-64-v3), where the cycle in
/// float ran 2.4x slower than on AVX-512 on the same host (docs/melt-core.md, issue 20 step 24).
/// The last group of a block that is not a multiple of eight is padded with dead slots (the
/// arrays of `out` hold whole groups).
template <class Real>
inline void triangle_block_terms(const TriMesh<Real>& m, const Real* packed, std::size_t first, std::size_t count,
                                 TriangleBlockTerms<Real>& out) {
  static_assert(kTriangleBlock % kLanes == 0);
  using L = Lanes<Real>;
  const std::uint8_t* const alive = m.triangle_alive.data() + first;
  const Triangle* const triangles = m.triangle.data() + first;
  auto group = [&](std::size_t i0, auto full_c) {
    constexpr bool kFull = decltype(full_c)::value;
    const std::size_t n = kFull ? kLanes : count - i0;
    // Offsets of the corners' packed triples (vertex 0 for a dead or padding slot).
    std::uint32_t offset[3][kLanes];
    std::uint8_t padded_alive[kLanes] = {};  // a partial group's flags, 0 past the end
    if constexpr (!kFull) std::copy_n(alive + i0, n, padded_alive);
    const std::uint8_t* const group_alive = kFull ? alive + i0 : padded_alive;
    for (std::size_t j = 0; j < kLanes; ++j) {
      const std::size_t i = i0 + (kFull ? j : std::min(j, n - 1));
      const std::uint32_t keep = group_alive[j] != 0 ? ~0u : 0u;
      for (std::size_t k = 0; k < 3; ++k) offset[k][j] = 3 * (static_cast<std::uint32_t>(triangles[i][k]) & keep);
    }
    const LaneMask<float> live = lanes_nonzero<float>(group_alive);
    L x[3], y[3], z[3];
    for (std::size_t k = 0; k < 3; ++k) gather_xyz<Real>(packed, offset[k], x[k], y[k], z[k]);
    const L abx = x[1] - x[0], aby = y[1] - y[0], abz = z[1] - z[0];
    const L bcx = x[2] - x[1], bcy = y[2] - y[1], bcz = z[2] - z[1];
    const L cax = x[0] - x[2], cay = y[0] - y[2], caz = z[0] - z[2];
    const L acx = x[2] - x[0], acy = y[2] - y[0], acz = z[2] - z[0];
    // Eq. 2.9: (b - a) x (c - a)
    const L nx = aby * acz - abz * acy;
    const L ny = abz * acx - abx * acz;
    const L nz = abx * acy - aby * acx;
    const L inv_n = lane_inverse_length<Real>(nx * nx + ny * ny + nz * nz);
    store_lanes<Real>(out.nx + i0, nx * inv_n);
    store_lanes<Real>(out.ny + i0, ny * inv_n);
    store_lanes<Real>(out.nz + i0, nz * inv_n);
    const L l0 = abx * abx + aby * aby + abz * abz;
    const L l1 = bcx * bcx + bcy * bcy + bcz * bcz;
    const L l2 = cax * cax + cay * cay + caz * caz;
    // std::min(std::min(l0, l1), l2), and +inf for a dead slot.
    const L l01 = lane_select<Real>(l1 < l0, l1, l0);
    const L shortest = lane_select<Real>(l2 < l01, l2, l01);
    const Lanes<float> dead_key =
        lane_select<float>(live, Lanes<float>{}, broadcast<float>(std::numeric_limits<float>::infinity()));
    store_lanes<float>(out.min_edge2 + i0, lane_float_at_most<Real>(shortest) + dead_key);
    const L i0l = lane_inverse_length<Real>(l0);
    const L i1l = lane_inverse_length<Real>(l1);
    const L i2l = lane_inverse_length<Real>(l2);
    store_lanes<Real>(out.ex[0] + i0, abx * i0l), store_lanes<Real>(out.ey[0] + i0, aby * i0l);
    store_lanes<Real>(out.ez[0] + i0, abz * i0l);
    store_lanes<Real>(out.ex[1] + i0, bcx * i1l), store_lanes<Real>(out.ey[1] + i0, bcy * i1l);
    store_lanes<Real>(out.ez[1] + i0, bcz * i1l);
    store_lanes<Real>(out.ex[2] + i0, cax * i2l), store_lanes<Real>(out.ey[2] + i0, cay * i2l);
    store_lanes<Real>(out.ez[2] + i0, caz * i2l);
  };
  const std::size_t grouped = count / kLanes * kLanes;
  for (std::size_t i0 = 0; i0 < grouped; i0 += kLanes) group(i0, std::true_type{});
  if (grouped < count) group(grouped, std::false_type{});
}

}  // namespace meltlab::sim
