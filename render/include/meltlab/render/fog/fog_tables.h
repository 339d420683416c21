#pragma once
// The tables of seed 002's fog model (spec fog-spotlight-airlight.md §2.6-2.7): F(u, v) for the
// airlight, and G_n(T, θ) for the fog's light reflected by a surface, each N×N with bilinear
// lookup, stored as one-channel float images (core/image.h, as the listing's float textures)
// and read with core's sample_bilinear (nodes at integer coordinates, clamped).
//
//   G_n(T, θ) = ∫_{Ω} e^{-T cos φ}/sin φ [F(T sin φ, π/2) - F(T sin φ, φ/2)] max(0, cos θ_i)^n dω_i
//
// with the pole at the light (φ: angle between ω_i and the light direction) and θ_i measured
// from the axis at angle θ from the light: the normal for Lambert (n = 1: the spec's G_0,
// eq. 3.21-3.22) or the mirrored view direction for Phong (n = 20: G_20, eq. 3.23). dω =
// sin φ dφ dψ cancels the 1/sin φ, so
//   G_n(T, θ) = ∫_0^π e^{-T cos φ} D_T(φ) W_n(φ, θ) dφ,   D_T(φ) = ∫_{φ/2}^{π/2} e^{-T sin φ tan ζ} dζ,
//   W_n(φ, θ) = ∫_0^{2π} max(0, cos φ cos θ + sin φ sin θ cos ψ)^n dψ   (closed form, binomial).
// W_n has kinks in φ at |π/2 - θ| and π - |π/2 - θ| (where the ring of directions at φ starts
// and stops crossing the hemisphere's edge); D_T(φ) behaves as φ ln φ at φ = 0. The φ integral is
// composite Gauss–Legendre (8 points per panel) on panels whose edges include the kinks and a
// geometric grading towards φ = 0; D_T from the accurate 1-D routine (fog/airlight_f.h), not a
// table. A table row (one T) shares its D_T values across all θ: the panel edges are the union of
// the kinks of every θ node.
//
// Domains and axis warps (fsa.table.*; describe() says them, the callers log it):
//   F: x = v in [0, π/2], y = u in [0, u_max = 20]; G: x = T in [0, T_max = 10], y = θ in [0, π].
//   An axis warp `sqrt` places nodes at lo + (hi - lo)(i/(N-1))² (dense near lo: the steep region
//   u -> 0 of F), `cbrt` at lo + (hi - lo)(i/(N-1))³, `sqrt_hi` at hi - (hi - lo)(1 - i/(N-1))²
//   (dense near hi: v -> π/2 of H); `none` uniformly. Beyond the domain the lookup clamps and
//   reports it.

#include <meltlab/core/image.h>

#include <string>

namespace meltlab::render::fog {

enum class AxisWarp {
  kNone,    ///< uniform nodes
  kSqrt,    ///< index ∝ sqrt((x - lo)/(hi - lo)): nodes at lo + (hi - lo) s², dense near lo
  kCbrt,    ///< index ∝ cbrt((x - lo)/(hi - lo)): nodes at lo + (hi - lo) s³, denser near lo
  kSqrtHi,  ///< nodes at hi - (hi - lo)(1 - s)²: dense near hi
  kSmooth,  ///< nodes at lo + (hi - lo)(3s² - 2s³): dense near both ends
};
const char* axis_warp_name(AxisWarp w);
AxisWarp parse_axis_warp(const std::string& name, const std::string& where);

/// Where bilinear interpolation is linear between two nodes (fsa.table.v_interp).
enum class InterpSpace {
  kIndex,  ///< in the warped coordinate (the node index): with `sqrt`, linear in √u
  kValue,  ///< in the axis variable itself (u, v) between its nodes: exact for a linear function
};
const char* interp_space_name(InterpSpace s);
InterpSpace parse_interp_space(const std::string& name, const std::string& where);

/// One axis of a table: n nodes from lo to hi (both included) with a warp.
struct TableAxis {
  std::string name;  ///< "v", "u", "T", "theta"
  double lo = 0, hi = 1;
  int n = 2;
  AxisWarp warp = AxisWarp::kNone;
  InterpSpace space = InterpSpace::kIndex;

  /// The value at node i (0..n-1).
  double node(int i) const;
  /// The continuous node index of x in [0, n-1]; sets `clamped` if x is beyond [lo, hi]
  /// (by more than 1e-12 relative: rounding at the ends is not counted). With space kValue the
  /// fraction within a cell is (x - node(i))/(node(i + 1) - node(i)); with kIndex, the warped
  /// coordinate's (the two agree for warp none).
  double index(double x, bool& clamped) const;
};

/// A tabulated function of two variables, bilinear between nodes.
struct FogTable {
  std::string name;  ///< "F", "G1" (the spec's G_0), "G20"
  TableAxis x, y;    ///< x: columns, y: rows
  ImageF values;     ///< x.n × y.n, one channel

  /// Bilinear lookup at (x, y), clamped to the domain; `clamped` (if given) is set to true when
  /// (x, y) lies beyond it (fsa.table.beyond_domain: clamp, flag).
  double lookup(double x, double y, bool* clamped = nullptr) const;
  /// "H: x = v in [0, 1.5708] (64 nodes, warp sqrt_hi, linear in value space), y = u in [0, 20]
  /// (64 nodes, warp cbrt, linear in index space), bilinear, ...".
  std::string describe() const;
};

/// Table resolution and domains (fsa.table.*).
struct TableOptions {
  int n = 64;                                  ///< fsa.table.N: nodes per axis
  double u_max = 20;                           ///< fsa.table.F.domain: u in [0, u_max]
  double t_max = 10;                           ///< fsa.table.G.domain: T in [0, t_max]
  AxisWarp u_warp = AxisWarp::kNone;           ///< fsa.table.axis_warp (F's and H's u axis)
  AxisWarp v_warp = AxisWarp::kNone;           ///< fsa.table.v_warp (F's and H's v axis)
  InterpSpace v_interp = InterpSpace::kIndex;  ///< fsa.table.v_interp (F's and H's v axis; u: index)
  AxisWarp t_warp = AxisWarp::kNone;           ///< the same for G's T axis
};

/// The F table on N×N nodes (entries from airlight_f; TBB over rows).
FogTable f_table(const TableOptions& o);

/// The H table (airlight_f.h's airlight_h: the tail of F with e^{-u tan v} factored out) on the
/// same axes as F (fsa.table.function = H). It stores K(u, v) = H(u, v)·h_scale(u, v),
/// h_scale = 1 + u tan v: H falls to 0 at v = π/2 as π/2 - v for u = 0 but as cos² v/u for
/// u > 0, where bilinear interpolation of H has a large relative error; K vanishes as π/2 - v
/// for every u (K = H exactly at u = 0, where H = π/2 - v is linear in v). On the S4 rays this
/// halves E2's maximum at N = 64 against storing H (0.117 -> 0.058; `meltlab fog bench`).
/// Read it with h_lookup.
FogTable h_table(const TableOptions& o);

/// 1 + u tan v, the scale between H and the H table's K.
double h_scale(double u, double v);

/// H(u, v) from an h_table: K bilinearly, divided by h_scale (0 at v >= π/2). Beyond u_max, K is
/// continued as K(u_max, v) (K tends to a function of v alone as u grows) and `clamped` is set.
double h_lookup(const FogTable& t, double u, double v, bool* clamped = nullptr);

/// G_n(T, θ) accurately (a single value; about 1 ms). exponent >= 1 (1 = Lambert's G_0).
double surface_g(int exponent, double T, double theta);

/// W_n(φ, θ) of the header comment (closed form: exact up to rounding, |error| < 1e-14).
double ring_weight(int exponent, double phi, double theta);

/// The G_n table on N×N nodes (rows in parallel; each row shares its D_T values).
FogTable g_table(int exponent, const TableOptions& o);

}  // namespace meltlab::render::fog
