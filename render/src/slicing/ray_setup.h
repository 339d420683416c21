#pragma once
// A slicing ray's set-up, written once for one ray (D = double) and for a packet's lanes (D =
// packet::VD), with the same operations in the same order (-ffp-contract=off: no fused
// multiply-add), so that a lane computes the bits of its ray alone: the pinhole's direction through
// a pixel, the planes the ray meets inside the box (ray_slices), the opacity correction's exponent
// and the fixed-point first position and move per plane (fixed_position.h). The packets set up
// eight rays with a few dozen vector instructions instead of eight calls of RayGenerator,
// ray_slices and intersect_box (a tenth of a frame's time before).
// The arithmetic is that of RayGenerator::generate_ray (an undistorted pinhole), ray_slices and
// intersect_box written out (dot products as (x + y) + z); a distorted pinhole's directions come
// from RayGenerator lane by lane, the rest from here.

#include "fixed_position.h"
#include "packet.h"

#include <meltlab/render/slicing/slice_geometry.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace meltlab::render::ray_setup {

/// What the set-up of every ray of a frame shares.
struct Frame {
  double cx = 0, cy = 0, fx = 1, fy = 1;  ///< the pinhole (pixels)
  double rot[3][3]{};                     ///< world_from_camera's rotation
  double eye[3]{};
  double n[3]{};            ///< the planes' normal
  double t_offset = 0;      ///< n · eye
  double lo[3]{}, hi[3]{};  ///< the volume's box
  double s_max = 0, spacing = 1;
  int count = 0;  ///< planes
  double origin[3]{}, inv_spacing[3]{};
  double h0 = 1;                   ///< the reference spacing of the opacity correction
  bool opacity_correction = true;  ///< false: exponent 1
  double sign = -1;                ///< +1 front to back, -1 back to front
};

/// The plane part of a Frame (normal, eye, box, stack) for rays from `eye`; the rest default.
inline Frame plane_frame(const SliceStack& st, const Box3& box, const Eigen::Vector3d& eye) {
  Frame f;
  for (int a = 0; a < 3; ++a) f.eye[a] = eye[a], f.n[a] = st.n[a], f.lo[a] = box.lo[a], f.hi[a] = box.hi[a];
  f.t_offset = (f.n[0] * f.eye[0] + f.n[1] * f.eye[1]) + f.n[2] * f.eye[2];
  f.s_max = st.s_max, f.spacing = st.spacing, f.count = st.count;
  return f;
}

namespace detail {
inline double sel(bool m, double a, double b) { return m ? a : b; }
inline packet::VD sel(packet::VL m, packet::VD a, packet::VD b) { return m ? a : b; }
inline int sel(bool m, int a, int b) { return m ? a : b; }
inline packet::VI sel(packet::VI m, packet::VI a, packet::VI b) { return m ? a : b; }
inline double sqrt_(double x) { return std::sqrt(x); }
inline packet::VD sqrt_(packet::VD x) { return packet::sqrt(x); }
inline double ceil_(double x) { return std::ceil(x); }
inline packet::VD ceil_(packet::VD x) { return packet::ceil(x); }
inline double floor_(double x) { return std::floor(x); }
inline packet::VD floor_(packet::VD x) { return packet::floor(x); }
/// An integral double in [-2^30, 2^30] (clamped) as an int.
inline int to_int(double x) { return int(std::clamp(x, -0x1p30, 0x1p30)); }
inline packet::VI to_int(packet::VD x) {
  x = x < -0x1p30 ? packet::splat(-0x1p30) : x;
  x = x > 0x1p30 ? packet::splat(0x1p30) : x;
  return __builtin_convertvector(x, packet::VI);
}
inline packet::VI narrow(packet::VL m) { return packet::narrow(m); }
inline bool narrow(bool m) { return m; }
inline bool not_(bool m) { return !m; }
inline packet::VL not_(packet::VL m) { return ~m; }
/// std::llrint (the current rounding mode: to nearest) as fixed_position.h's from_double.
inline std::uint64_t fixed_of(double x) { return fixed::from_double(x); }
inline packet::VU fixed_of(packet::VD x) {
  x = x * fixed::kOne;
#if defined(__AVX512DQ__) && MELTLAB_PACKET_LANES == 8
  return packet::VU(_mm512_cvtpd_epi64(__m512d(x)));
#else
  packet::VU r;
  for (int l = 0; l < packet::kLanes; ++l) r[l] = std::uint64_t(std::llrint(x[l]));
  return r;
#endif
}
}  // namespace detail

/// The unit direction of the undistorted pinhole's ray through pixel (x, y) (pixel centres at
/// integers): R (x', y', 1) / |R (x', y', 1)| with x' = (x - cx) / fx, y' = (y - cy) / fy.
template <class D>
inline void pinhole_direction(const Frame& f, D x, D y, D (&v)[3]) {
  using detail::sel;
  const D xn = (x - f.cx) / f.fx, yn = (y - f.cy) / f.fy;
  D d[3];
  for (int a = 0; a < 3; ++a) d[a] = (f.rot[a][0] * xn + f.rot[a][1] * yn) + f.rot[a][2] * 1.0;
  const D n2 = (d[0] * d[0] + d[1] * d[1]) + d[2] * d[2];
  const D len = detail::sqrt_(n2);
  for (int a = 0; a < 3; ++a) v[a] = sel(n2 > 0.0, d[a] / len, d[a]);
}

/// The planes rays from the eye with unit directions v meet inside the box (one ray or a packet's
/// lanes; ray_slices is this for one ray).
template <class D>
struct Planes {
  using I = decltype(detail::to_int(D{}));
  D cos_psi{};                 ///< n · v
  I k_first{}, k_last{};       ///< the planes inside the box (k_first > k_last: none)
  decltype(D{} < D{}) miss{};  ///< no plane: the ray misses the box or looks away from the planes
};

/// The slab test (intersect_box's arithmetic), then the planes between the box's near and far
/// points along the ray (s_k = s_max - (k + 1/2) Δd in [s(t0), s(t1)]).
template <class D>
inline Planes<D> planes_of(const Frame& f, const D (&v)[3]) {
  using detail::sel;
  Planes<D> r;
  r.cos_psi = (f.n[0] * v[0] + f.n[1] * v[1]) + f.n[2] * v[2];
  // intersect_box: the slabs, an axis the ray does not move on must contain the eye.
  D t0 = D{} - std::numeric_limits<double>::infinity(), t1 = D{} + std::numeric_limits<double>::infinity();
  auto miss = detail::not_(r.cos_psi > 0.0);
  for (int a = 0; a < 3; ++a) {
    const auto still = v[a] == 0.0;
    if (f.eye[a] < f.lo[a] || f.eye[a] > f.hi[a]) miss = miss | still;
    const D tn = (f.lo[a] - f.eye[a]) / v[a], tf = (f.hi[a] - f.eye[a]) / v[a];
    const auto swap = tn > tf;
    const D tmin = sel(swap, tf, tn), tmax = sel(swap, tn, tf);
    t0 = sel(still, t0, sel(t0 < tmin, tmin, t0));  // std::max(t0, tn)
    t1 = sel(still, t1, sel(tmax < t1, tmax, t1));  // std::min(t1, tf)
  }
  miss = miss | (t0 > t1) | (t1 < 0.0);
  t0 = sel(t0 < 0.0, D{} + 0.0, t0);  // std::max(t0, 0.0)
  const D s_near = f.t_offset + t0 * r.cos_psi, s_far = f.t_offset + t1 * r.cos_psi;
  using I = typename Planes<D>::I;
  const I kf = detail::to_int(detail::ceil_((f.s_max - s_far) / f.spacing - 0.5));
  const I kl = detail::to_int(detail::floor_((f.s_max - s_near) / f.spacing - 0.5));
  const auto missing = detail::narrow(miss);
  r.k_first = detail::sel(missing, I{} + 0, detail::sel(kf < 0, I{} + 0, kf));
  r.k_last = detail::sel(missing, I{} - 1, detail::sel(kl > f.count - 1, I{} + (f.count - 1), kl));
  r.miss = miss;
  return r;
}

/// The set-up of rays from the eye with unit directions v (one or a packet's lanes).
template <class D>
struct Rays : Planes<D> {
  using U = decltype(detail::fixed_of(D{}));
  D exponent{};        ///< (Δd / cos ψ) / h0, or 1 without opacity correction
  U g0[3]{}, dg[3]{};  ///< the first plane's position and the move per plane (fixed point)
};

/// The planes (planes_of) and the fixed-point positions from the first plane of the walk's order
/// (the farthest back to front).
template <class D>
inline Rays<D> rays_from(const Frame& f, const D (&v)[3]) {
  using detail::sel;
  Rays<D> r;
  static_cast<Planes<D>&>(r) = planes_of(f, v);
  const auto miss = r.miss;
  using I = typename Planes<D>::I;
  // The walk's first plane and the move per plane; the exponent of the opacity correction.
  const D along = f.spacing / r.cos_psi;
  r.exponent = f.opacity_correction ? along / f.h0 : D{} + 1.0;
  const I k_start = f.sign > 0 ? r.k_last : r.k_first;
  D kd;
  if constexpr (std::is_same_v<D, double>)
    kd = double(k_start);
  else
    kd = __builtin_convertvector(k_start, D);
  const D t = ((f.s_max - (kd + 0.5) * f.spacing) - f.t_offset) / r.cos_psi;
  const D step = f.sign * along;
  for (int a = 0; a < 3; ++a) {
    D delta = step * (v[a] * f.inv_spacing[a]);
    delta = sel(delta < -0x1p30, D{} - 0x1p30, sel(delta > 0x1p30, D{} + 0x1p30, delta));
    const D g = ((f.eye[a] + t * v[a]) - f.origin[a]) * f.inv_spacing[a];
    // Rays without planes: any finite values (never used).
    r.g0[a] = detail::fixed_of(sel(miss, D{} + 0.0, g));
    r.dg[a] = detail::fixed_of(sel(miss, D{} + 0.0, delta));
  }
  return r;
}

}  // namespace meltlab::render::ray_setup

#pragma GCC diagnostic pop
