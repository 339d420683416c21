#pragma once
// Private to sim/src (the melt cycle, and the per-cycle statistics in mesh/mesh_stats.cpp): eight
// lanes of a real number as one SIMD value (GCC/Clang vector extension; the compiler maps it to
// the machine's registers: one AVX register for float, one AVX-512 register or two AVX registers
// for double) and the shuffles that move data between per-element records and lanes:
//   - transpose8: eight records of eight numbers <-> eight lanes of one number each;
//   - deinterleave3 / interleave3: eight packed xyz triples (Vec3 arrays) <-> x, y, z lanes;
//   - gather_xyz: eight four-number records at scattered offsets -> x, y, z lanes.
// Arithmetic on lanes is element by element with the same IEEE operations as scalar code
// (contraction is off), so a lane's result is bitwise the scalar result.

// Lanes of double are 64-byte vectors. Without AVX-512 (a build for another machine, e.g.
// -DMELTLAB_NATIVE=OFF -march=x86-64-v3) GCC notes that passing them by value changes the ABI,
// and -Werror turns the note into a build failure. They are passed only between inline functions
// of one translation unit, never across objects, so the note does not apply. The pragma is not
// popped: the note fires where the melt's .cpp files instantiate those functions, and only they
// include this private header.
#pragma GCC diagnostic ignored "-Wpsabi"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#if defined(__AVX__)
#include <immintrin.h>
#endif

namespace meltlab::sim {

inline constexpr std::size_t kLanes = 8;

template <class Real>
struct LaneTypes {
  using Value [[gnu::vector_size(kLanes * sizeof(Real))]] = Real;
  using Int = std::conditional_t<sizeof(Real) == 4, std::int32_t, std::int64_t>;
  /// What a comparison of two Values gives: all bits set (true) or zero, per lane.
  using Mask [[gnu::vector_size(kLanes * sizeof(Real))]] = Int;
};

#if defined(__AVX2__) && !defined(__AVX512F__)
// Without AVX-512 a 64-byte vector of doubles has no machine mode: GCC 12 keeps it in memory and
// lowers selects, comparisons and element moves lane by lane through the stack (the double cycle
// ran 2.9x slower than with AVX-512 on the same Zen 4, 1.4x more than float lost). So there eight
// doubles are two AVX registers: a struct of two 4-lane vectors with the vector extension's
// operators, each applied to both halves (the same IEEE operation per lane, so the same bits).
namespace lanes_detail {
using V4d = double __attribute__((vector_size(32)));
using V4l = std::int64_t __attribute__((vector_size(32)));

/// Eight lane masks (all bits set where true), as two halves.
struct MaskD8 {
  V4l h[2];
  std::int64_t operator[](std::size_t i) const { return h[i >> 2][i & 3]; }
  friend MaskD8 operator&(const MaskD8& a, const MaskD8& b) { return {{a.h[0] & b.h[0], a.h[1] & b.h[1]}}; }
  friend MaskD8 operator|(const MaskD8& a, const MaskD8& b) { return {{a.h[0] | b.h[0], a.h[1] | b.h[1]}}; }
  friend MaskD8 operator~(const MaskD8& a) { return {{~a.h[0], ~a.h[1]}}; }
  MaskD8& operator|=(const MaskD8& b) { return *this = *this | b; }
};

/// Eight doubles as two halves.
struct LanesD8 {
  V4d h[2];
  LanesD8() = default;
  LanesD8(double a0, double a1, double a2, double a3, double a4, double a5, double a6, double a7)
      : h{{a0, a1, a2, a3}, {a4, a5, a6, a7}} {}
  double operator[](std::size_t i) const { return h[i >> 2][i & 3]; }
  // (GCC gives a vector the alias set of its elements: a double lvalue may name a lane.)
  double& operator[](std::size_t i) { return reinterpret_cast<double*>(h)[i]; }
  LanesD8& operator+=(const LanesD8& b) { return h[0] += b.h[0], h[1] += b.h[1], *this; }
  LanesD8 operator-() const { return pair(-h[0], -h[1]); }
  static LanesD8 pair(V4d lo, V4d hi) {
    LanesD8 r;
    r.h[0] = lo, r.h[1] = hi;
    return r;
  }
};
#define MELTLAB_LANES_D8_OP(op)                                                                              \
  inline LanesD8 operator op(const LanesD8& a, const LanesD8& b) {                                           \
    return LanesD8::pair(a.h[0] op b.h[0], a.h[1] op b.h[1]);                                                \
  }                                                                                                          \
  inline LanesD8 operator op(const LanesD8& a, double b) { return LanesD8::pair(a.h[0] op b, a.h[1] op b); } \
  inline LanesD8 operator op(double a, const LanesD8& b) { return LanesD8::pair(a op b.h[0], a op b.h[1]); }
MELTLAB_LANES_D8_OP(+)
MELTLAB_LANES_D8_OP(-)
MELTLAB_LANES_D8_OP(*)
MELTLAB_LANES_D8_OP(/)
#undef MELTLAB_LANES_D8_OP
#define MELTLAB_LANES_D8_CMP(op)                                                                                   \
  inline MaskD8 operator op(const LanesD8& a, const LanesD8& b) { return {{a.h[0] op b.h[0], a.h[1] op b.h[1]}}; } \
  inline MaskD8 operator op(const LanesD8& a, double b) { return {{a.h[0] op b, a.h[1] op b}}; }                   \
  inline MaskD8 operator op(double a, const LanesD8& b) { return {{a op b.h[0], a op b.h[1]}}; }
MELTLAB_LANES_D8_CMP(<)
MELTLAB_LANES_D8_CMP(>)
MELTLAB_LANES_D8_CMP(<=)
MELTLAB_LANES_D8_CMP(>=)
MELTLAB_LANES_D8_CMP(==)
MELTLAB_LANES_D8_CMP(!=)
#undef MELTLAB_LANES_D8_CMP
}  // namespace lanes_detail

template <>
struct LaneTypes<double> {
  using Value = lanes_detail::LanesD8;
  using Int = std::int64_t;
  using Mask = lanes_detail::MaskD8;
};
#endif

template <class Real>
using Lanes = typename LaneTypes<Real>::Value;
template <class Real>
using LaneMask = typename LaneTypes<Real>::Mask;

template <class Real>
inline Lanes<Real> load_lanes(const Real* p) {
  Lanes<Real> v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
template <class Real>
inline void store_lanes(Real* p, const Lanes<Real>& v) {
  std::memcpy(p, &v, sizeof(v));
}
template <class Real>
inline Lanes<Real> broadcast(Real x) {
  return Lanes<Real>{} + x;
}

/// m ? a : b lane by lane (m from a comparison of lanes). Lane code selects with this, not with
/// ?:, which cannot be overloaded for the two-register doubles.
template <class Real>
inline Lanes<Real> lane_select(const LaneMask<Real>& m, const Lanes<Real>& a, const Lanes<Real>& b) {
  return m ? a : b;
}

/// Lane-wise sqrt (exactly rounded, like std::sqrt; compiles to one SIMD instruction).
template <class Real>
inline Lanes<Real> lane_sqrt(Lanes<Real> x) {
  for (std::size_t i = 0; i < kLanes; ++i) x[i] = std::sqrt(x[i]);
  return x;
}

#if defined(__AVX2__) && !defined(__AVX512F__)
template <>
inline Lanes<double> lane_select<double>(const LaneMask<double>& m, const Lanes<double>& a, const Lanes<double>& b) {
  return Lanes<double>::pair(m.h[0] ? a.h[0] : b.h[0], m.h[1] ? a.h[1] : b.h[1]);
}
template <>
inline Lanes<double> lane_sqrt<double>(Lanes<double> x) {
  return Lanes<double>::pair(lanes_detail::V4d(_mm256_sqrt_pd(__m256d(x.h[0]))),
                             lanes_detail::V4d(_mm256_sqrt_pd(__m256d(x.h[1]))));
}
#endif

/// 1/|v| for |v|² = n2, or 0 for a zero vector, lane by lane: the same operations as the
/// scalar 1 / sqrt(max(n2, smallest normal)), and 0 where n2 > 0 is false (a degenerate triangle or
/// a vanished edge contributes nothing instead of NaN).
template <class Real>
inline Lanes<Real> lane_inverse_length(Lanes<Real> n2) {
  const Lanes<Real> tiny = broadcast(std::numeric_limits<Real>::min());
  const Lanes<Real> inv = Real(1) / lane_sqrt<Real>(lane_select<Real>(n2 < tiny, tiny, n2));
  return lane_select<Real>(n2 > Real(0), inv, Lanes<Real>{});
}

/// Lane-wise |x| and max(a, b) (as std::max: a unless a < b).
template <class Real>
inline Lanes<Real> lane_abs(Lanes<Real> x) {
  return lane_select<Real>(x < Real(0), -x, x);
}
template <class Real>
inline Lanes<Real> lane_max(Lanes<Real> a, Lanes<Real> b) {
  return lane_select<Real>(a < b, b, a);
}

/// Each lane rounded to float (as static_cast<float>).
inline Lanes<float> lanes_to_float(const Lanes<double>& x) {
#if defined(__AVX2__) && !defined(__AVX512F__)
  using V4f = float __attribute__((vector_size(16)));
  const V4f lo = V4f(_mm256_cvtpd_ps(__m256d(x.h[0]))), hi = V4f(_mm256_cvtpd_ps(__m256d(x.h[1])));
  return __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7);
#else
  return __builtin_convertvector(x, Lanes<float>);
#endif
}

/// Lanes of Real from eight 32-bit integers, and the lane mask of eight bytes that are not zero.
template <class Real>
inline Lanes<Real> lanes_from_ints(const std::int32_t* p) {
  if constexpr (!std::is_class_v<Lanes<Real>>) {
    using Ints [[gnu::vector_size(kLanes * sizeof(std::int32_t))]] = std::int32_t;
    Ints v;
    std::memcpy(&v, p, sizeof(v));
    return __builtin_convertvector(v, Lanes<Real>);
  } else {
    using Half [[gnu::vector_size(4 * sizeof(std::int32_t))]] = std::int32_t;
    using HalfReal [[gnu::vector_size(4 * sizeof(Real))]] = Real;
    Half lo, hi;
    std::memcpy(&lo, p, sizeof(lo));
    std::memcpy(&hi, p + 4, sizeof(hi));
    return Lanes<Real>::pair(__builtin_convertvector(lo, HalfReal), __builtin_convertvector(hi, HalfReal));
  }
}
template <class Real>
inline LaneMask<Real> lanes_nonzero(const std::uint8_t* p) {
  if constexpr (!std::is_class_v<LaneMask<Real>>) {
    using Bytes [[gnu::vector_size(kLanes)]] = std::uint8_t;
    Bytes b;
    std::memcpy(&b, p, sizeof(b));
    return __builtin_convertvector(b, LaneMask<Real>) != 0;
  } else {
    using Half [[gnu::vector_size(4)]] = std::uint8_t;
    using HalfMask [[gnu::vector_size(4 * sizeof(std::int64_t))]] = std::int64_t;
    Half lo, hi;
    std::memcpy(&lo, p, sizeof(lo));
    std::memcpy(&hi, p + 4, sizeof(hi));
    return {{__builtin_convertvector(lo, HalfMask) != 0, __builtin_convertvector(hi, HalfMask) != 0}};
  }
}

/// Bit i set where lane i of m is true (one instruction for float lanes on AVX).
template <class Real>
inline unsigned lane_bits(const LaneMask<Real>& m) {
#if defined(__AVX__)
  if constexpr (std::is_same_v<Real, float>) return static_cast<unsigned>(_mm256_movemask_ps(__m256(m)));
#endif
  // (Written as `(m[i] != 0 ? 1u : 0u) << i`, GCC 12 with -fsanitize=undefined returned wrong bits for
  // double lanes: 0 for a mask of 0xfe, checked by Lanes8.LaneBitsAreTheLanesOfAMask in build/asan.)
  unsigned bits = 0;
  for (std::size_t i = 0; i < kLanes; ++i) bits |= static_cast<unsigned>(m[i] != 0) << i;
  return bits;
}

/// Writes first + i for every bit i set in `bits` (of eight), ascending, to out[0], out[1], ...,
/// and returns how many: without a branch per bit where AVX-512 can compress a vector of
/// indices (out must then have room for eight).
inline std::size_t append_bit_indices(unsigned bits, std::int32_t first, std::int32_t* out) {
#if defined(__AVX512F__) && defined(__AVX512VL__)
  const __m256i index = _mm256_add_epi32(_mm256_set1_epi32(first), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  // The register form: compressing straight to memory is microcoded and slow on Zen 4.
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out), _mm256_maskz_compress_epi32(static_cast<__mmask8>(bits), index));
  return static_cast<std::size_t>(__builtin_popcount(bits & 0xffu));
#else
  std::size_t n = 0;
  for (; bits != 0; bits &= bits - 1) out[n++] = first + __builtin_ctz(bits);
  return n;
#endif
}

/// Transposes an 8×8 block: out[j][i] = in[i][j] (records <-> lanes).
template <class Real>
[[gnu::always_inline]] inline void transpose8(const Lanes<Real> (&in)[kLanes], Lanes<Real> (&out)[kLanes]) {
  // Three stages of two-input shuffles (the classic unpack / shuffle / 128-bit permute).
  Lanes<Real> t[kLanes], u[kLanes];
  for (std::size_t i = 0; i < kLanes; i += 2) {
    t[i] = __builtin_shufflevector(in[i], in[i + 1], 0, 8, 1, 9, 4, 12, 5, 13);
    t[i + 1] = __builtin_shufflevector(in[i], in[i + 1], 2, 10, 3, 11, 6, 14, 7, 15);
  }
  for (std::size_t i = 0; i < kLanes; i += 4) {
    u[i] = __builtin_shufflevector(t[i], t[i + 2], 0, 1, 8, 9, 4, 5, 12, 13);
    u[i + 1] = __builtin_shufflevector(t[i], t[i + 2], 2, 3, 10, 11, 6, 7, 14, 15);
    u[i + 2] = __builtin_shufflevector(t[i + 1], t[i + 3], 0, 1, 8, 9, 4, 5, 12, 13);
    u[i + 3] = __builtin_shufflevector(t[i + 1], t[i + 3], 2, 3, 10, 11, 6, 7, 14, 15);
  }
  for (std::size_t j = 0; j < 4; ++j) {
    out[j] = __builtin_shufflevector(u[j], u[j + 4], 0, 1, 2, 3, 8, 9, 10, 11);
    out[j + 4] = __builtin_shufflevector(u[j], u[j + 4], 4, 5, 6, 7, 12, 13, 14, 15);
  }
}

/// Eight packed triples p[3i + c] (i < 8, c < 3) -> lanes x[i], y[i], z[i].
template <class Real>
inline void deinterleave3(const Real* p, Lanes<Real>& x, Lanes<Real>& y, Lanes<Real>& z) {
  const Lanes<Real> a = load_lanes(p), b = load_lanes(p + kLanes), c = load_lanes(p + 2 * kLanes);
  x = __builtin_shufflevector(__builtin_shufflevector(a, b, 0, 3, 6, 9, 12, 15, 0, 0), c, 0, 1, 2, 3, 4, 5, 10, 13);
  y = __builtin_shufflevector(__builtin_shufflevector(a, b, 1, 4, 7, 10, 13, 0, 0, 0), c, 0, 1, 2, 3, 4, 8, 11, 14);
  z = __builtin_shufflevector(__builtin_shufflevector(a, b, 2, 5, 8, 11, 14, 0, 0, 0), c, 0, 1, 2, 3, 4, 9, 12, 15);
}

/// The first three numbers of eight four-number records base + offset[i] (i < 8) -> lanes x[i],
/// y[i], z[i]: eight 4-number loads joined in pairs (i, i + 4) and three stages of two-input
/// shuffles. (Without AVX-512, double lanes are two registers: see the specialisation below.)
template <class Real>
inline void gather_xyz(const Real* base, const std::uint32_t (&offset)[kLanes], Lanes<Real>& x, Lanes<Real>& y,
                       Lanes<Real>& z) {
  using Quad [[gnu::vector_size(4 * sizeof(Real))]] = Real;
  Quad q[kLanes];
  for (std::size_t i = 0; i < kLanes; ++i) std::memcpy(&q[i], base + offset[i], sizeof(Quad));
  const Lanes<Real> a04 = __builtin_shufflevector(q[0], q[4], 0, 1, 2, 3, 4, 5, 6, 7);
  const Lanes<Real> a15 = __builtin_shufflevector(q[1], q[5], 0, 1, 2, 3, 4, 5, 6, 7);
  const Lanes<Real> a26 = __builtin_shufflevector(q[2], q[6], 0, 1, 2, 3, 4, 5, 6, 7);
  const Lanes<Real> a37 = __builtin_shufflevector(q[3], q[7], 0, 1, 2, 3, 4, 5, 6, 7);
  // x0 x1 y0 y1 x4 x5 y4 y5 | z0 z1 w0 w1 z4 z5 w4 w5, and the same of records 2, 3, 6, 7.
  const Lanes<Real> t0 = __builtin_shufflevector(a04, a15, 0, 8, 1, 9, 4, 12, 5, 13);
  const Lanes<Real> t1 = __builtin_shufflevector(a04, a15, 2, 10, 3, 11, 6, 14, 7, 15);
  const Lanes<Real> t2 = __builtin_shufflevector(a26, a37, 0, 8, 1, 9, 4, 12, 5, 13);
  const Lanes<Real> t3 = __builtin_shufflevector(a26, a37, 2, 10, 3, 11, 6, 14, 7, 15);
  x = __builtin_shufflevector(t0, t2, 0, 1, 8, 9, 4, 5, 12, 13);
  y = __builtin_shufflevector(t0, t2, 2, 3, 10, 11, 6, 7, 14, 15);
  z = __builtin_shufflevector(t1, t3, 0, 1, 8, 9, 4, 5, 12, 13);
}

/// Lanes x, y, z -> eight packed triples p[3i + c].
template <class Real>
inline void interleave3(Real* p, const Lanes<Real>& x, const Lanes<Real>& y, const Lanes<Real>& z) {
  store_lanes(
      p, __builtin_shufflevector(__builtin_shufflevector(x, y, 0, 8, 0, 1, 9, 0, 2, 10), z, 0, 1, 8, 3, 4, 9, 6, 7));
  store_lanes(p + kLanes, __builtin_shufflevector(__builtin_shufflevector(x, y, 0, 3, 11, 0, 4, 12, 0, 5), z, 10, 1, 2,
                                                  11, 4, 5, 12, 7));
  store_lanes(p + 2 * kLanes, __builtin_shufflevector(__builtin_shufflevector(x, y, 13, 0, 6, 14, 0, 7, 15, 0), z, 0,
                                                      13, 2, 3, 14, 5, 6, 15));
}

#if defined(__AVX2__) && !defined(__AVX512F__)
// Without AVX-512, eight doubles are two AVX registers, and GCC 12 lowers a 64-byte
// __builtin_shufflevector lane by lane through the stack (on a Zen 3 host the vertex moves ran
// 550 single-lane stores and reloads for 48 multiplications; docs/melt-core.md, issue 20 step 14).
// So the double shuffles below work on the two 256-bit halves with AVX2's own shuffles. They move
// the same numbers to the same lanes as the generic forms above (tests/sim/lane_moves_test.cpp
// checks both precisions against index arithmetic).
namespace lanes_detail {
inline void split(const Lanes<double>& v, __m256d& lo, __m256d& hi) { lo = __m256d(v.h[0]), hi = __m256d(v.h[1]); }
inline Lanes<double> join(__m256d lo, __m256d hi) { return Lanes<double>::pair(V4d(lo), V4d(hi)); }
/// c[j][i] = r[i][j] for a 4×4 block.
inline void transpose4(const __m256d (&r)[4], __m256d (&c)[4]) {
  const __m256d t0 = _mm256_unpacklo_pd(r[0], r[1]), t1 = _mm256_unpackhi_pd(r[0], r[1]);
  const __m256d t2 = _mm256_unpacklo_pd(r[2], r[3]), t3 = _mm256_unpackhi_pd(r[2], r[3]);
  c[0] = _mm256_permute2f128_pd(t0, t2, 0x20), c[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
  c[2] = _mm256_permute2f128_pd(t0, t2, 0x31), c[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
}
}  // namespace lanes_detail

template <>
inline void transpose8<double>(const Lanes<double> (&in)[kLanes], Lanes<double> (&out)[kLanes]) {
  // Rows 0-3 and 4-7, columns 0-3 (lo) and 4-7 (hi): out[j] = (column j of rows 0-3, of rows 4-7).
  __m256d lo[2][4], hi[2][4], a[4], b[4], c[4], d[4];
  for (std::size_t i = 0; i < kLanes; ++i) lanes_detail::split(in[i], lo[i / 4][i % 4], hi[i / 4][i % 4]);
  lanes_detail::transpose4(lo[0], a);
  lanes_detail::transpose4(lo[1], b);
  lanes_detail::transpose4(hi[0], c);
  lanes_detail::transpose4(hi[1], d);
  for (std::size_t j = 0; j < 4; ++j)
    out[j] = lanes_detail::join(a[j], b[j]), out[j + 4] = lanes_detail::join(c[j], d[j]);
}

template <>
inline void deinterleave3<double>(const double* p, Lanes<double>& x, Lanes<double>& y, Lanes<double>& z) {
  // Four triples at a time: a = x0 y0 z0 x1, b = y1 z1 x2 y2, c = z2 x3 y3 z3; blends bring each
  // coordinate's four values into one register, a permute puts them in order.
  __m256d xs[2], ys[2], zs[2];
  for (int h = 0; h < 2; ++h) {
    const __m256d a = _mm256_loadu_pd(p + 12 * h), b = _mm256_loadu_pd(p + 12 * h + 4),
                  c = _mm256_loadu_pd(p + 12 * h + 8);
    xs[h] = _mm256_permute4x64_pd(_mm256_blend_pd(_mm256_blend_pd(a, b, 0b0100), c, 0b0010), 0x6C);  // a0 a3 b2 c1
    ys[h] = _mm256_permute4x64_pd(_mm256_blend_pd(_mm256_blend_pd(a, b, 0b1001), c, 0b0100), 0xB1);  // a1 b0 b3 c2
    zs[h] = _mm256_permute4x64_pd(_mm256_blend_pd(_mm256_blend_pd(a, b, 0b0010), c, 0b1001), 0xC6);  // a2 b1 c0 c3
  }
  x = lanes_detail::join(xs[0], xs[1]), y = lanes_detail::join(ys[0], ys[1]), z = lanes_detail::join(zs[0], zs[1]);
}

template <>
inline void interleave3<double>(double* p, const Lanes<double>& x, const Lanes<double>& y, const Lanes<double>& z) {
  // deinterleave3's steps backwards (its three permutes are their own inverses).
  __m256d xs[2], ys[2], zs[2];
  lanes_detail::split(x, xs[0], xs[1]);
  lanes_detail::split(y, ys[0], ys[1]);
  lanes_detail::split(z, zs[0], zs[1]);
  for (int h = 0; h < 2; ++h) {
    const __m256d X = _mm256_permute4x64_pd(xs[h], 0x6C), Y = _mm256_permute4x64_pd(ys[h], 0xB1),
                  Z = _mm256_permute4x64_pd(zs[h], 0xC6);
    _mm256_storeu_pd(p + 12 * h, _mm256_blend_pd(_mm256_blend_pd(X, Y, 0b0010), Z, 0b0100));
    _mm256_storeu_pd(p + 12 * h + 4, _mm256_blend_pd(_mm256_blend_pd(Y, Z, 0b0010), X, 0b0100));
    _mm256_storeu_pd(p + 12 * h + 8, _mm256_blend_pd(_mm256_blend_pd(Z, X, 0b0010), Y, 0b0100));
  }
}

template <>
inline void gather_xyz<double>(const double* base, const std::uint32_t (&offset)[kLanes], Lanes<double>& x,
                               Lanes<double>& y, Lanes<double>& z) {
  // Records 0-3 and 4-7, each four doubles: two 4×4 transposes.
  __m256d r[2][4], c[2][4];
  for (std::size_t i = 0; i < kLanes; ++i) r[i / 4][i % 4] = _mm256_loadu_pd(base + offset[i]);
  lanes_detail::transpose4(r[0], c[0]);
  lanes_detail::transpose4(r[1], c[1]);
  x = lanes_detail::join(c[0][0], c[1][0]), y = lanes_detail::join(c[0][1], c[1][1]);
  z = lanes_detail::join(c[0][2], c[1][2]);
}
#endif

}  // namespace meltlab::sim
