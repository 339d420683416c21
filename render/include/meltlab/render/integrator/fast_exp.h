#pragma once
// A float exponential for the compositing loops of the volume integrator.

#include <cmath>
#include <cstdint>
#include <cstring>

namespace meltlab::render {

/// e^x for x <= 0 in float, inline: Cody–Waite range reduction x = n ln2 + r (|r| <= ln2/2) and a
/// degree-6 polynomial for e^r; relative error < 3e-7 = 2.5 ulp (tested against std::exp), 0 at
/// and below -87.
/// The compositing loop calls it once per sample; glibc's expf is a call the loop cannot
/// overlap with its neighbours.
inline float exp_nonpositive(float x) {
  if (!(x > -87.0f)) return 0.0f;
  const float n = std::nearbyint(x * 1.44269504088896341f);
  const float r = std::fma(n, 2.12194440e-4f, std::fma(n, -0.693359375f, x));
  // Horner with explicit fused multiply-adds (the build turns off implicit contraction): half the
  // latency of the chain, and the same bits on every machine with FMA.
  float p = 1.3981999507e-3f;
  p = std::fma(p, r, 8.3334519073e-3f);
  p = std::fma(p, r, 4.1665795894e-2f);
  p = std::fma(p, r, 1.6666665459e-1f);
  p = std::fma(p, r, 5.0000001201e-1f);
  p = std::fma(p * r, r, r) + 1.0f;
  const std::int32_t bits = (std::int32_t(n) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

}  // namespace meltlab::render
