#pragma once
// x^y, and the opacity correction 1 - (1 - α)^e built on it (corrected_alpha; corrected_alpha_f in
// float, at the end), on one double (float) or on eight lanes (packet::VD, packet::VF) with the same
// operations in the same order, so that a lane computes the bits of the scalar call: the slicing
// renderer's corrected α per sample of the linear TF (e = Δ/h0 along the ray; in float) and per ray
// and piece of the constant TF, which the packets would otherwise compute with std::pow lane by lane.
// pow is not std::pow's bits: within (16 + 4 |y ln x|) 2^-53 of it relative while the result is
// normal (slicing_speed_test).
//
// For x >= 0 and y >= 0, both finite (what the renderer passes): x = m 2^k with m in [√½, √2)
// (subnormal x scaled by 2^54 first), ln x = k ln 2 + 2 atanh(s), s = (m - 1) / (m + 1) (m - 1 is
// exact by Sterbenz' lemma; |s| <= 0.1716, the odd series to s^23, whose next term is < 1e-18 of
// the sum), t = y ln x, then e^t = 2^j e^r with j = round(t / ln 2), r = t - j ln2_hi - j ln2_lo
// (Cody and Waite's split: j ln2_hi is exact for |j| < 2^20) and e^r by its Taylor polynomial to
// r^15 (|r| <= 0.347: the next term is < 1e-17), scaled by 2^j in two steps where the result is
// subnormal. pow(0, y > 0) = 0 and x^0 = 1 (0^0 included) as std::pow; t < -745.2 gives 0, t > 709
// (x > 1 with a huge y: not passed by the renderer) infinity.
// Every operation is a single IEEE operation (the translation unit has -ffp-contract=off; the
// polynomials' fused multiply-adds are written as std::fma and packet::fma, one rounding each),
// and the floor of the lanes rounds as std::floor: one double and its lane give the same bits.

#include "packet.h"

#include <bit>
#include <cmath>
#include <cstdint>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace meltlab::render::lane_math {

namespace detail {

// The operations that differ between a double and eight lanes.
inline double floor_(double x) { return std::floor(x); }
inline double fma_(double a, double b, double c) { return std::fma(a, b, c); }
inline packet::VD fma_(packet::VD a, packet::VD b, packet::VD c) { return packet::fma(a, b, c); }
inline float fma_(float a, float b, float c) { return std::fma(a, b, c); }
inline packet::VF fma_(packet::VF a, packet::VF b, packet::VF c) { return packet::fma(a, b, c); }
inline packet::VD floor_(packet::VD x) { return packet::floor(x); }
inline double sel(bool m, double a, double b) { return m ? a : b; }
inline packet::VD sel(packet::VL m, packet::VD a, packet::VD b) { return m ? a : b; }
inline std::int64_t bits_of(double x) { return std::bit_cast<std::int64_t>(x); }
inline packet::VL bits_of(packet::VD x) { return packet::VL(x); }  // (vector casts keep the bits)
inline double from_bits(std::int64_t b) { return std::bit_cast<double>(b); }
inline packet::VD from_bits(packet::VL b) { return packet::VD(b); }
inline double to_double(std::int64_t i) { return double(i); }
inline packet::VD to_double(packet::VL i) { return __builtin_convertvector(i, packet::VD); }
inline std::int64_t to_int(double x) { return std::int64_t(x); }
inline packet::VL to_int(packet::VD x) { return __builtin_convertvector(x, packet::VL); }

/// 2^j as a double for integer j in [-1022, 1023] (I: std::int64_t or packet::VL).
template <class I>
inline auto exp2i(I j) {
  return from_bits(I((j + 1023) << 52));
}

}  // namespace detail

/// x^y for x >= 0, y >= 0 finite (see the header); D is double or packet::VD.
template <class D>
inline D pow(D x, D y) {
  using namespace detail;
  using I = decltype(bits_of(x));
  constexpr double kSqrt2 = 1.4142135623730951;
  constexpr double kLn2Hi = 6.93147180369123816490e-01, kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kInvLn2 = 1.44269504088896338700e+00;
  const D zero_d = D{} + 0.0, one_d = D{} + 1.0;
  // ln x = k ln 2 + ln m.
  const auto tiny = x < 0x1p-1022;
  const I b = bits_of(sel(tiny, x * 0x1p54, x));
  D m = from_bits(I((b & 0x000fffffffffffffLL) | 0x3ff0000000000000LL));  // [1, 2)
  const auto big = m > kSqrt2;
  m = sel(big, m * 0.5, m);
  const D kd = to_double(I(((b >> 52) & 0x7ff) - 1023)) - sel(tiny, D{} + 54.0, zero_d) + sel(big, one_d, zero_d);
  const D f = m - 1.0;
  const D s = f / (2.0 + f), s2 = s * s;
  D q = D{} + 1.0 / 23;
  for (int n = 21; n >= 1; n -= 2) q = fma_(q, s2, D{} + 1.0 / n);
  const D ln_x = kd * kLn2Hi + (kd * kLn2Lo + 2.0 * s * q);
  // e^t = 2^j e^r.
  D t = y * ln_x;
  const auto under = t<-745.2, over = t> 709.0;
  t = sel(under | over, zero_d, t);
  const D jd = floor_(t * kInvLn2 + 0.5);
  const D r = (t - jd * kLn2Hi) - jd * kLn2Lo;
  double fact = 1307674368000.0;  // 15!
  D p = D{} + 1.0 / fact;
  for (int n = 14; n >= 0; --n) {
    fact /= double(n + 1);  // n! (integers below 2^53: exact)
    p = fma_(p, r, D{} + 1.0 / fact);
  }
  // 2^j in two steps where the result is subnormal (j >= -1076 here).
  const auto sub = jd < -1000.0;
  const D e = p * exp2i(to_int(jd + sel(sub, D{} + 100.0, zero_d))) * sel(sub, D{} + 0x1p-100, one_d);
  const D out = sel(under, zero_d, sel(over, D{} + HUGE_VAL, e));
  return sel(y == 0.0, one_d, sel(x == 0.0, zero_d, out));
}

/// The integer exponent int_pow() takes where the specular exponent y is one (1 <= y <= kMaxIntPow),
/// else 0 (then pow()).
inline constexpr int kMaxIntPow = 1024;
inline int int_exponent(double y) { return y >= 1 && y <= kMaxIntPow && y == std::floor(y) ? int(y) : 0; }

/// x^n for x >= 0 and an integer n in [1, kMaxIntPow] (Blinn-Phong's usual exponents) by binary
/// exponentiation: per bit of n from the lowest, the result times the power where the bit is set,
/// then the power squared, every product one rounding in one order for a double and its lanes. The
/// relative error grows by at most one rounding per product and doubles with each squaring: below
/// 2 n 2^-53 while the result is normal, so rounded to float it is x^n correctly rounded but within
/// 2 n 2^-53 of a float rounding boundary. Cheaper than pow() (log, exp) by far: for n = 32 five
/// squarings. D is double or packet::VD.
template <class D>
inline D int_pow(D x, int n) {
  D result = D{} + 1.0, power = x;
  for (;;) {
    if (n & 1) result = result * power;
    n >>= 1;
    if (n == 0) return result;
    power = power * power;
  }
}

/// The lit modes' specular power x^y: int_pow(x, n) where n = int_exponent(y) > 0, else pow(x, y).
template <class D>
inline D specular_power(D x, int n, double y) {
  return n > 0 ? int_pow(x, n) : pow(x, D{} + y);
}

namespace detail {

// The small-α branch of corrected_alpha(): t = e ln(1 - a) and α' = -(e^t - 1), each by a short
// series, for a <= kSmallAlpha and |t| <= kSmallT. 1 - a = (1 + s) / (1 - s) with s = a / (a - 2)
// (|s| <= 1/63; a - 2 loses at most half an ulp, relative), ln(1 - a) = 2 s (1 + s²/3 + ... + s⁸/9):
// the first term left out is s^10 / 11 < 1e-19 of the sum. e^t - 1 = t (1 + t/2! + ... + t⁸/9!): the
// first term left out is t⁹/10! < 2e-17 of the sum. Every step rounds once (fma_), so α' is within a
// few ulps of itself relative: more accurate than 1 - (1 - a)^e, which rounds 1 - a and cancels.
inline constexpr double kSmallAlpha = 1.0 / 32, kSmallT = 1.0 / 16;

template <class D>
inline D small_alpha_t(D a, D e) {
  const D s = a / (a - 2.0), z = s * s;
  D q = D{} + 1.0 / 9;
  for (int n = 7; n >= 1; n -= 2) q = fma_(q, z, D{} + 1.0 / n);
  return e * ((2.0 * s) * q);
}

template <class D>
inline D small_alpha_from_t(D t) {
  static constexpr double kInvFact[9] = {1.0 / 1,   1.0 / 2,    1.0 / 6,     1.0 / 24,    1.0 / 120,
                                         1.0 / 720, 1.0 / 5040, 1.0 / 40320, 1.0 / 362880};  // 1/(n+1)!
  D p = D{} + kInvFact[8];
  for (int n = 7; n >= 0; --n) p = fma_(p, t, D{} + kInvFact[n]);
  return -(t * p);
}

}  // namespace detail

/// The opacity correction α' = 1 - (1 - a)^e for a in [0, 1] and e >= 0 finite: by the short series
/// above where a <= 1/32 and |e ln(1 - a)| <= 1/16 (translucent TFs at moderate QC: every sample of
/// the seed-003 scenes at QC 1), else 1 - pow(1 - a, e). Within (4 + e) 2^-53 of 1 - std::pow(1 - a, e)
/// absolute (slicing_speed_test). One double, or the packet's lanes (the same operations per lane,
/// so a lane gives the double's bits), where `need` marks the lanes whose result is used: pow runs
/// only if one of them leaves the short branch.
inline double corrected_alpha(double a, double e) {
  using namespace detail;
  if (a <= kSmallAlpha) {
    const double t = small_alpha_t(a, e);
    if (std::abs(t) <= kSmallT) return small_alpha_from_t(t);
  }
  return 1.0 - pow(1.0 - a, e);
}

inline packet::VD corrected_alpha(packet::VD a, packet::VD e, packet::VL need) {
  using namespace detail;
  const packet::VD t = small_alpha_t(a, e);
  const packet::VL small = (a <= kSmallAlpha) & (t <= kSmallT) & (t >= -kSmallT);
  const packet::VD fast = small_alpha_from_t(t);
  if (!packet::any(packet::narrow(need & ~small))) return fast;
  return sel(small, fast, 1.0 - pow(1.0 - a, e));
}

namespace detail {

// The float form of the short branch (corrected_alpha_f): the same series, cut where float's
// precision ends. ln(1 - a) = 2 s (1 + s²/3 + s⁴/5): the first term left out is s⁶/7 < 3e-12 of
// the sum (|s| <= 1/63); e^t - 1 = t (1 + t/2! + t²/3! + t³/4! + t⁴/5!): the first term left out is
// t⁵/6! < 2e-9 of the sum (|t| <= 1/16); float's unit round-off is 2^-24 ≈ 6e-8.
template <class F>
inline F small_alpha_t_f(F a, F e) {
  const F s = a / (a - 2.0f), z = s * s;
  const F q = fma_(fma_(F{} + 1.0f / 5, z, F{} + 1.0f / 3), z, F{} + 1.0f);
  return e * ((2.0f * s) * q);
}

template <class F>
inline F small_alpha_from_t_f(F t) {
  F p = F{} + 1.0f / 120;
  for (const float c : {1.0f / 24, 1.0f / 6, 1.0f / 2, 1.0f}) p = fma_(p, t, F{} + c);
  return -(t * p);
}

}  // namespace detail

/// corrected_alpha in float, for the linear TF's per-sample α (the sample and the TF are evaluated
/// in float; issue 17's thirteenth round): the short series above where a <= 1/32 and |t| <= 1/16
/// (within 8 2^-24 of -expm1(e log1p(-a)) relative, tested), else the double corrected_alpha rounded
/// to float. One float, or the lanes (each lane the float's bits; `need` as above).
inline float corrected_alpha_f(float a, float e) {
  using namespace detail;
  if (a <= float(kSmallAlpha)) {
    const float t = small_alpha_t_f(a, e);
    if (std::abs(t) <= float(kSmallT)) return small_alpha_from_t_f(t);
  }
  return float(corrected_alpha(double(a), double(e)));
}

inline packet::VF corrected_alpha_f(packet::VF a, packet::VF e, packet::VI need) {
  using namespace detail;
  const packet::VF t = small_alpha_t_f(a, e);
  const packet::VI small = (a <= float(kSmallAlpha)) & (t <= float(kSmallT)) & (t >= -float(kSmallT));
  const packet::VF fast = small_alpha_from_t_f(t);
  const packet::VI slow = need & ~small;
  if (!packet::any(slow)) return fast;
  const packet::VD full = corrected_alpha(__builtin_convertvector(a, packet::VD),
                                          __builtin_convertvector(e, packet::VD), packet::wide(slow));
  return packet::select(small, fast, __builtin_convertvector(full, packet::VF));
}

}  // namespace meltlab::render::lane_math

#pragma GCC diagnostic pop
