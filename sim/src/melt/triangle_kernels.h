#pragma once
// Private to the melt cycle: the per-triangle arithmetic of Alg. 1, computed a
// block of triangles at a time. Corner positions are first gathered (from a packed copy of
// the position columns) into structure-of-arrays
// buffers, then plain loops over them do the arithmetic (the compiler turns these into
// SIMD instructions: sqrt and division are exactly rounded in SIMD too, and contraction is
// off, so the result of every element is the same as a scalar evaluation). Serial and
// parallel execution call the same kernels, so their results are bitwise identical.

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
  std::size_t count = 0;
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
// loop for double: 1.4-1.7x slower cycles, measured.)
template <class Real>
inline float float_at_most(Real x) {
  static_assert(std::numeric_limits<float>::is_iec559 && std::numeric_limits<double>::is_iec559);
  if constexpr (std::is_same_v<Real, float>)
    return x;
  else
    return static_cast<float>(x * (1.0 - 0x1p-23));
}

// 1/|v| for |v|² = n2, or 0 for a zero vector (`zero_guard`: a degenerate triangle or a
// vanished edge contributes nothing instead of NaN). Written without a branch on a
// division so that it vectorises: max() keeps the division finite and the multiplication
// by (n2 > 0) zeroes the result for a zero vector. For n2 >= the smallest normal number
// this is exactly 1/sqrt(n2).
template <class Real>
inline Real inverse_length(Real n2) {
  constexpr Real kTiny = std::numeric_limits<Real>::min();
  const Real inv = Real(1) / std::sqrt(std::max(n2, kTiny));
  return n2 > Real(0) ? inv : Real(0);
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
/// three corners: a point, whose normal and edges inverse_length() turns into zero terms.
template <class Real>
inline void triangle_block_terms(const TriMesh<Real>& m, const Real* packed, std::size_t first, std::size_t count,
                                 TriangleBlockTerms<Real>& out) {
  // Corners copied as four-number records (one 16/32-byte load each: the packed triple and
  // the number after it), then split into x, y, z arrays for the arithmetic below, which
  // vectorises over them.
  Real p[3][kTriangleBlock][4];
  float dead_key[kTriangleBlock];  // added to the key: 0, or +inf for a dead slot
  out.count = count;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t t = first + i;
    const bool alive = m.triangle_alive[t] != 0;
    dead_key[i] = alive ? 0.0f : std::numeric_limits<float>::infinity();
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t v = alive ? static_cast<std::size_t>(m.triangle[t][k]) : 0;
      std::memcpy(p[k][i], packed + 3 * v, 4 * sizeof(Real));
    }
  }
  Real px[3][kTriangleBlock], py[3][kTriangleBlock], pz[3][kTriangleBlock];
  for (std::size_t k = 0; k < 3; ++k)
    for (std::size_t i = 0; i < count; ++i) {
      px[k][i] = p[k][i][0];
      py[k][i] = p[k][i][1];
      pz[k][i] = p[k][i][2];
    }
  for (std::size_t i = 0; i < count; ++i) {
    const Real abx = px[1][i] - px[0][i], aby = py[1][i] - py[0][i], abz = pz[1][i] - pz[0][i];
    const Real bcx = px[2][i] - px[1][i], bcy = py[2][i] - py[1][i], bcz = pz[2][i] - pz[1][i];
    const Real cax = px[0][i] - px[2][i], cay = py[0][i] - py[2][i], caz = pz[0][i] - pz[2][i];
    const Real acx = px[2][i] - px[0][i], acy = py[2][i] - py[0][i], acz = pz[2][i] - pz[0][i];
    // Eq. 2.9: (b - a) x (c - a)
    const Real nx = aby * acz - abz * acy;
    const Real ny = abz * acx - abx * acz;
    const Real nz = abx * acy - aby * acx;
    const Real inv_n = inverse_length(nx * nx + ny * ny + nz * nz);
    out.nx[i] = nx * inv_n;
    out.ny[i] = ny * inv_n;
    out.nz[i] = nz * inv_n;
    const Real l0 = abx * abx + aby * aby + abz * abz;
    const Real l1 = bcx * bcx + bcy * bcy + bcz * bcz;
    const Real l2 = cax * cax + cay * cay + caz * caz;
    out.min_edge2[i] = float_at_most(std::min(std::min(l0, l1), l2)) + dead_key[i];
    const Real i0 = inverse_length(l0);
    const Real i1 = inverse_length(l1);
    const Real i2 = inverse_length(l2);
    out.ex[0][i] = abx * i0, out.ey[0][i] = aby * i0, out.ez[0][i] = abz * i0;
    out.ex[1][i] = bcx * i1, out.ey[1][i] = bcy * i1, out.ez[1][i] = bcz * i1;
    out.ex[2][i] = cax * i2, out.ey[2][i] = cay * i2, out.ez[2][i] = caz * i2;
  }
}

}  // namespace meltlab::sim
