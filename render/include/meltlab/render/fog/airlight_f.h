#pragma once
// The medium-independent function of seed 002's airlight (spec fog-spotlight-airlight.md §2.4,
// eq. 3.16), evaluated accurately (for the references, the tables and the tests):
//
//   F(u, v) = ∫_0^v exp(-u tan ζ) dζ = ∫_0^{tan v} exp(-u w) / (1 + w²) dw,
//   u >= 0 (u = k_t·h, dimensionless), 0 <= v <= π/2 (radians).
//
// The airlight of a view-ray segment [a, b] is A0 [F(A1, v_b) - F(A1, v_a)] (spec eq. 3.17;
// render/fog/airlight.h). F(u, π/2) = Ci(u) sin u - (Si(u) - π/2) cos u (DLMF §6.2's auxiliary
// function f), F(0, v) = v, ∂F/∂v = exp(-u tan v).
//
// Method: the w-form, split at w = 1 and w = 1/u (the two scales of the integrand: the
// Lorentzian 1/(1 + w²) and the cut-off exp(-u w)); pieces beyond w = 1 are integrated in
// r = ln w, where both scales are smooth; each piece by Boost.Math's adaptive Gauss–Kronrod
// 15/7 to a relative tolerance of 1e-13. Where exp(-u w) has underflowed (u w > 745) the
// integrand is zero and the range ends. Relative accuracy about 1e-13 over the whole domain
// (tests/render/fog/airlight_f_test.cpp checks it against the ζ-form by tanh-sinh and against
// Si/Ci).

namespace meltlab::render::fog {

/// F(u, v) of eq. 3.16. u >= 0, v in [0, π/2] (values up to 1e-12 beyond either end of v are
/// clamped; anything else throws InvariantError: a caller's bug).
double airlight_f(double u, double v);

/// F(u, v1) - F(u, v0) = ∫_{v0}^{v1} exp(-u tan ζ) dζ integrated directly (no cancellation
/// when v0 and v1 are close or both near π/2). 0 <= v0 <= v1 <= π/2.
double airlight_f_between(double u, double v0, double v1);

/// The tail with its exponential factored out (the harness's table function, fsa.table.function = H):
///   H(u, v) = e^{u tan v} ∫_v^{π/2} e^{-u tan ζ} dζ = ∫_0^∞ e^{-u s} / (1 + (tan v + s)²) ds,
/// so that F(u, v_b) - F(u, v_a) = e^{-u tan v_a} H(u, v_a) - e^{-u tan v_b} H(u, v_b). Smooth and
/// bounded (H <= π/2 - v, H(0, v) = π/2 - v, H ~ cos² v / u for large u); with the airlight's
/// prefactor the exponentials become e^{-k_t (x + d_x)}, the attenuation light -> x -> eye.
double airlight_h(double u, double v);

/// ∂F/∂v = exp(-u tan v) (the integrand; 0 at v = π/2 for u > 0).
double airlight_f_dv(double u, double v);

}  // namespace meltlab::render::fog
