#pragma once
// Packets for the slicing renderer's SIMD path (slicing_renderer.cpp, SlicingSettings::simd): GCC
// vector extensions of one register of doubles each — eight lanes where the target has AVX-512,
// four where it has AVX (a 64-byte vector on an AVX2-only target is lowered lane by lane through
// the stack: the packets ran 1.24x slower than one ray at a time on a Zen 3 host) — and the
// target's gather and fused multiply-add instructions where it has them (a loop over the lanes
// otherwise).
// Every operation rounds as its scalar counterpart in the renderer does (-ffp-contract=off: no
// fused multiply-add unless written as fma), so a lane computes the bits a scalar ray would.

#include <cstdint>

#if defined(__AVX2__) || defined(__AVX512F__) || defined(__FMA__)
#include <immintrin.h>
#endif

#include <cmath>
#include <type_traits>

// The packets are passed between inline functions of one translation unit only; GCC's note that
// 64-byte vectors change the ABI without AVX-512 does not apply.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace meltlab::render::packet {

#if defined(__AVX512F__)
#define MELTLAB_PACKET_LANES 8
#else
#define MELTLAB_PACKET_LANES 4
#endif
constexpr int kLanes = MELTLAB_PACKET_LANES;
/// A packet's pixels: a block of kLanesX x 2 (lane l at x0 + l % kLanesX, y0 + l / kLanesX).
constexpr int kLanesX = kLanes / 2;
using VD = double __attribute__((vector_size(8 * kLanes)));        ///< eight doubles
using VL = std::int64_t __attribute__((vector_size(8 * kLanes)));  ///< masks of VD (-1 true, 0 false)
using VF = float __attribute__((vector_size(4 * kLanes)));         ///< eight floats
using VI = std::int32_t __attribute__((vector_size(4 * kLanes)));  ///< eight ints, masks of VF
/// Fixed-point positions (32.32 bits, wrapping adds and products: exact wherever the true value
/// fits, as it does for a lane inside its planes) and 64-bit words.
using VU = std::uint64_t __attribute__((vector_size(8 * kLanes)));

inline VD splat(double x) { return VD{} + x; }
inline VF splatf(float x) { return VF{} + x; }
inline VI splati(std::int32_t x) { return VI{} + x; }

/// An int mask (-1/0) widened to the mask of doubles.
inline VL wide(VI m) { return __builtin_convertvector(m, VL); }
inline VI narrow(VL m) { return __builtin_convertvector(m, VI); }
/// Bit l set where lane l of a mask is true.
inline unsigned bits(VI m) {
#if defined(__AVX__) && MELTLAB_PACKET_LANES == 8
  return unsigned(_mm256_movemask_ps(__m256(m)));
#elif defined(__AVX__)
  return unsigned(_mm_movemask_ps(__m128(m)));
#else
  unsigned r = 0;
  for (int l = 0; l < kLanes; ++l) r |= (m[l] != 0 ? 1u : 0u) << l;
  return r;
#endif
}
inline bool any(VI m) { return bits(m) != 0; }
inline int count(VI m) { return __builtin_popcount(bits(m)); }
/// The sum of the lanes.
inline std::int32_t hsum(VI x) {
  std::int32_t r = 0;
  for (int l = 0; l < kLanes; ++l) r += x[l];
  return r;
}
/// The smallest lane.
inline std::int32_t hmin(VI x) {
#if defined(__AVX2__)
#if MELTLAB_PACKET_LANES == 8
  __m128i m = _mm_min_epi32(_mm256_castsi256_si128(__m256i(x)), _mm256_extracti128_si256(__m256i(x), 1));
#else
  __m128i m = __m128i(x);
#endif
  m = _mm_min_epi32(m, _mm_shuffle_epi32(m, 0x4E));
  m = _mm_min_epi32(m, _mm_shuffle_epi32(m, 0xB1));
  return _mm_cvtsi128_si32(m);
#else
  std::int32_t r = x[0];
  for (int l = 1; l < kLanes; ++l) r = x[l] < r ? x[l] : r;
  return r;
#endif
}
/// Bit l in lane l.
inline VI lane_bits() {
  VI r;
  for (int l = 0; l < kLanes; ++l) r[l] = 1 << l;
  return r;
}

/// m ? a : b per lane.
inline VD select(VL m, VD a, VD b) { return m ? a : b; }
inline VI select(VI m, VI a, VI b) { return m ? a : b; }
inline VF select(VI m, VF a, VF b) { return m ? a : b; }

/// i clamped to [0, hi] per lane (hi >= 0): select(i < 0, 0, select(i > hi, hi, i)), by one max
/// and one min where the target has them.
inline VI clamp(VI i, VI hi) {
#if defined(__AVX2__) && MELTLAB_PACKET_LANES == 8
  return VI(_mm256_min_epi32(_mm256_max_epi32(__m256i(i), _mm256_setzero_si256()), __m256i(hi)));
#elif defined(__AVX2__)
  return VI(_mm_min_epi32(_mm_max_epi32(__m128i(i), _mm_setzero_si128()), __m128i(hi)));
#else
  return select(i < 0, splati(0), select(i > hi, hi, i));
#endif
}

/// std::fma per lane (one rounding).
inline VD fma(VD a, VD b, VD c) {
#if defined(__AVX512F__)
  return VD(_mm512_fmadd_pd(__m512d(a), __m512d(b), __m512d(c)));
#elif defined(__FMA__)
  return VD(_mm256_fmadd_pd(__m256d(a), __m256d(b), __m256d(c)));
#else
  VD r;
  for (int l = 0; l < kLanes; ++l) r[l] = std::fma(a[l], b[l], c[l]);
  return r;
#endif
}

/// std::fma per lane on floats (one rounding).
inline VF fma(VF a, VF b, VF c) {
#if defined(__FMA__) && MELTLAB_PACKET_LANES == 8
  return VF(_mm256_fmadd_ps(__m256(a), __m256(b), __m256(c)));
#elif defined(__FMA__)
  return VF(_mm_fmadd_ps(__m128(a), __m128(b), __m128(c)));
#else
  VF r;
  for (int l = 0; l < kLanes; ++l) r[l] = std::fma(a[l], b[l], c[l]);
  return r;
#endif
}

/// std::floor per lane for |x| < 2^31 (sample positions): truncate, then one down where that rose.
inline VF floor(VF x) {
  const VF t = __builtin_convertvector(__builtin_convertvector(x, VI), VF);
  return t - (t > x ? splatf(1.0f) : splatf(0.0f));
}

/// x rounded per lane to an integer towards -inf (kMode _MM_FROUND_TO_NEG_INF: std::floor) or +inf
/// (_MM_FROUND_TO_POS_INF: std::ceil), doubles.
template <int kMode>
inline VD round_to(VD x) {
#if defined(__AVX512F__)
  // (The masked form with x as the source: GCC 12 flags the unmasked one's undefined source.)
  return VD(_mm512_mask_roundscale_pd(__m512d(x), 0xFF, __m512d(x), kMode | _MM_FROUND_NO_EXC));
#elif defined(__AVX__)
  return VD(_mm256_round_pd(__m256d(x), kMode | _MM_FROUND_NO_EXC));
#else
  VD r;
  for (int l = 0; l < kLanes; ++l) r[l] = kMode == 0x01 ? std::floor(x[l]) : std::ceil(x[l]);
  return r;
#endif
}
inline VD floor(VD x) { return round_to<0x01>(x); }  // _MM_FROUND_TO_NEG_INF
inline VD ceil(VD x) { return round_to<0x02>(x); }   // _MM_FROUND_TO_POS_INF

/// std::sqrt per lane (correctly rounded, as the scalar one).
inline VD sqrt(VD x) {
#if defined(__AVX512F__)
  return VD(_mm512_mask_sqrt_pd(__m512d(x), 0xFF, __m512d(x)));  // (masked: see floor)
#elif defined(__AVX__)
  return VD(_mm256_sqrt_pd(__m256d(x)));
#else
  VD r;
  for (int l = 0; l < kLanes; ++l) r[l] = std::sqrt(x[l]);
  return r;
#endif
}

/// std::sqrt per lane on floats (correctly rounded, as the scalar one).
inline VF sqrt(VF x) {
#if defined(__AVX__) && MELTLAB_PACKET_LANES == 8
  return VF(_mm256_sqrt_ps(__m256(x)));
#elif defined(__SSE__)
  return VF(_mm_sqrt_ps(__m128(x)));
#else
  VF r;
  for (int l = 0; l < kLanes; ++l) r[l] = std::sqrt(x[l]);
  return r;
#endif
}

/// data[offset] per lane as float (offset 0 in lanes that do not need a value: any valid index).
template <class T>
inline VF gather(const T* data, VI offset) {
#if defined(__AVX2__)
  if constexpr (std::is_same_v<T, float>) {
#if MELTLAB_PACKET_LANES == 8
    return VF(_mm256_i32gather_ps(reinterpret_cast<const float*>(data), __m256i(offset), 4));
#else
    return VF(_mm_i32gather_ps(reinterpret_cast<const float*>(data), __m128i(offset), 4));
#endif
  }
#endif
  VF r;
  for (int l = 0; l < kLanes; ++l) r[l] = static_cast<float>(data[offset[l]]);
  return r;
}

/// data[offset] and data[offset + 1] per lane (neighbouring floats; offset + 1 must be valid in
/// every lane): one 64-bit gather where the target has it.
inline void gather_pairs(const float* data, VI offset, VF& first, VF& second) {
#if defined(__AVX512F__)
  // (The masked forms with a zero source: GCC 12 flags the unmasked ones' undefined source.)
  // The pairs' 32-bit halves split by one permute each (element 2l: data[offset], 2l + 1: the next).
  using V16 = float __attribute__((vector_size(64)));
  const V16 p = V16(_mm512_mask_i32gather_epi64(_mm512_setzero_si512(), 0xFF, __m256i(offset), data, 4));
  first = __builtin_shufflevector(p, p, 0, 2, 4, 6, 8, 10, 12, 14);
  second = __builtin_shufflevector(p, p, 1, 3, 5, 7, 9, 11, 13, 15);
#elif defined(__AVX2__)
  using V8 = float __attribute__((vector_size(32)));
  const V8 p = V8(_mm256_i32gather_epi64(reinterpret_cast<const long long*>(data), __m128i(offset), 4));
  first = __builtin_shufflevector(p, p, 0, 2, 4, 6);
  second = __builtin_shufflevector(p, p, 1, 3, 5, 7);
#else
  for (int l = 0; l < kLanes; ++l) first[l] = data[offset[l]], second[l] = data[offset[l] + 1];
#endif
}

/// data[offset] per lane (int32 table).
inline VI gather_i32(const std::int32_t* data, VI offset) {
#if defined(__AVX2__) && MELTLAB_PACKET_LANES == 8
  return VI(_mm256_i32gather_epi32(reinterpret_cast<const int*>(data), __m256i(offset), 4));
#elif defined(__AVX2__)
  return VI(_mm_i32gather_epi32(reinterpret_cast<const int*>(data), __m128i(offset), 4));
#else
  VI r;
  for (int l = 0; l < kLanes; ++l) r[l] = data[offset[l]];
  return r;
#endif
}

/// data[offset] per lane (bytes; each offset must be followed by 3 readable bytes: one 32-bit gather).
inline VI gather_u8(const std::uint8_t* data, VI offset) {
#if defined(__AVX2__) && MELTLAB_PACKET_LANES == 8
  return VI(_mm256_i32gather_epi32(reinterpret_cast<const int*>(data), __m256i(offset), 1)) & 255;
#elif defined(__AVX2__)
  return VI(_mm_i32gather_epi32(reinterpret_cast<const int*>(data), __m128i(offset), 1)) & 255;
#else
  VI r;
  for (int l = 0; l < kLanes; ++l) r[l] = data[offset[l]];
  return r;
#endif
}

/// data[index] per lane (64-bit words).
inline VU gather_u64(const std::uint64_t* data, VI index) {
#if defined(__AVX512F__) && MELTLAB_PACKET_LANES == 8
  // (The masked form with a zero source: see gather_pairs.)
  return VU(_mm512_mask_i32gather_epi64(_mm512_setzero_si512(), 0xFF, __m256i(index), data, 8));
#elif defined(__AVX2__)
  return VU(_mm256_i32gather_epi64(reinterpret_cast<const long long*>(data), __m128i(index), 8));
#else
  VU r;
  for (int l = 0; l < kLanes; ++l) r[l] = data[index[l]];
  return r;
#endif
}

}  // namespace meltlab::render::packet

#pragma GCC diagnostic pop
