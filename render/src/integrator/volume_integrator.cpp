// The volume integrator (see integrator/volume_integrator.h).

#include <meltlab/core/time.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/integrator/fast_exp.h>

#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>

#include "volume_tracer_state.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>

namespace meltlab::render {

using detail::SampleGrid;
using detail::TracerState;

namespace {

using Vec3 = Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kMaxLights = 16;

void validate_settings(const VolumeRenderSettings& s);

void validate(const Volume& volume, const VolumeRenderSettings& s) {
  if (volume.empty()) throw InputError("volume render: the volume is empty");
  validate_settings(s);
  if (s.model == OpticalModel::kTransferFunction)
    detail::validate_tf(s, false);
  else if (s.traversal == Traversal::kObjectOrder)
    throw InputError(
        "volume render: the object-order traversal renders the transfer_function model of a bricked volume");
}

void validate_settings(const VolumeRenderSettings& s) {
  auto bad = [](const std::string& what) { throw InputError("volume render: " + what); };
  if (s.samples < 1) bad(fmt::format("vlr.sampling.n must be >= 1 (got {})", s.samples));
  if (s.step_rule == StepRule::kFitSegment && !(s.step > 0 && std::isfinite(s.step)))
    bad("the fit_segment step rule needs sampling.step > 0");
  if (s.step_rule == StepRule::kFixedStep && !(s.step > 0 && std::isfinite(s.step)))
    bad("the fixed_step rule needs sampling.step > 0");
  if (!(s.kappa >= 0 && std::isfinite(s.kappa))) bad(fmt::format("kappa must be finite and >= 0 (got {})", s.kappa));
  if (!(s.gamma > 0 && std::isfinite(s.gamma))) bad(fmt::format("gamma must be finite and > 0 (got {})", s.gamma));
  if (!(s.hg_c > -1 && s.hg_c < 1)) bad(fmt::format("vlr.hg.c must be in (-1, 1) (got {})", s.hg_c));
  if (!(s.albedo >= 0 && std::isfinite(s.albedo))) bad("vlr.albedo must be finite and >= 0");
  if (!(s.shadow_step >= 0 && std::isfinite(s.shadow_step))) bad("vlr.shadow.step must be finite and >= 0");
  if (!(s.shadow_start_offset >= 0 && s.shadow_start_offset <= 1))
    bad("vlr.shadow.start_offset must be in [0, 1] (a fraction of the shadow step)");
  if (!(s.shadow_cache_scale > 0 && s.shadow_cache_scale <= 8)) bad("the shadow cache scale must be in (0, 8]");
  if (!(s.ert_transmittance >= 0 && s.ert_transmittance < 1)) bad("the ERT transmittance must be in [0, 1)");
  if (s.quadrature == Quadrature::kExponential && !s.emission_scale_by_ds)
    bad("vlr.emission.scale_by_ds = false needs the inclusive or exclusive quadrature (the exponential rule "
        "integrates each step)");
  if (!s.emission.allFinite() || !s.emission_rim.allFinite() || !s.background.allFinite() || !s.ambient.allFinite())
    bad("colours must be finite");
  if ((s.ambient.array() < 0).any()) bad("the ambient radiance must be >= 0");
  for (const auto& l : s.lights) {
    if (!l.intensity.allFinite() || (l.intensity.array() < 0).any()) bad("light intensities must be finite and >= 0");
    if (l.type == LightType::kDirectional && !(l.to_light.allFinite() && l.to_light.norm() > 0))
      bad("a directional light needs a non-zero direction");
    if (l.type == LightType::kPoint && !l.position.allFinite()) bad("a point light needs a finite position");
  }
}

/// Macrocells of kB³ samples for empty-space skipping: a macrocell is live when some sample that
/// a trilinear stencil located in it may read — the kB + 1 samples from its first, widened by one
/// sample each side to absorb rounding in locating points — has a value > 0 (values <= 0 count as
/// empty: e = 0). A point whose stencil's lower corner lies in a dead macrocell has f <= 0 exactly.
///
/// reach[c] is the radius of the cube of macrocells around c that all share c's state (live or
/// dead): r when every macrocell within L∞ distance r of c (inside the grid) has c's state, capped
/// at kMaxReach. A ray then runs (live) or jumps (dead) to the faces of that cube at once instead
/// of stopping at every macrocell face — the "proximity clouds" of Cohen & Sheffer (1994) in the
/// Chebyshev metric. Where no macrocell is dead, a live run spans the whole grid.
struct Macrocells {
  static constexpr int kB = 4;
  static constexpr int kMaxReach = 12;
  int bx = 0, by = 0, bz = 0;
  std::vector<std::uint8_t> live;   // empty: skipping disabled
  std::vector<std::uint8_t> reach;  // per macrocell, see above

  bool enabled() const { return !live.empty(); }
  std::size_t index(int cx, int cy, int cz) const {
    return std::size_t(cx) + std::size_t(bx) * (std::size_t(cy) + std::size_t(by) * std::size_t(cz));
  }
};

/// The Chebyshev distance, capped at cap, from every cell of a bx × by × bz grid to the nearest cell
/// with target set: d(p) = min over q with target(q) of max_i |p_i − q_i|, in three separable passes
/// d ← min_q max(|p − q|, d(q)) along x, y and z (exact for the L∞ metric).
std::vector<std::uint8_t> chebyshev_distance(const std::vector<std::uint8_t>& target, int bx, int by, int bz, int cap) {
  const int n[3] = {bx, by, bz};
  std::vector<std::uint8_t> d(target.size());
  for (std::size_t c = 0; c < target.size(); ++c) d[c] = target[c] ? 0 : std::uint8_t(cap);
  std::vector<std::uint8_t> next(d.size());
  const std::size_t stride[3] = {1, std::size_t(bx), std::size_t(bx) * std::size_t(by)};
  for (int ax = 0; ax < 3; ++ax) {
    const int u = ax == 0 ? 1 : 0, w = ax == 2 ? 1 : 2;  // the two other axes
    tbb::parallel_for(tbb::blocked_range<int>(0, n[w]), [&](const tbb::blocked_range<int>& r) {
      for (int b = r.begin(); b < r.end(); ++b)
        for (int a = 0; a < n[u]; ++a) {
          const std::size_t base = std::size_t(a) * stride[u] + std::size_t(b) * stride[w];
          for (int p = 0; p < n[ax]; ++p) {
            int best = d[base + std::size_t(p) * stride[ax]];
            const int q0 = std::max(0, p - cap), q1 = std::min(n[ax] - 1, p + cap);
            for (int q = q0; q <= q1 && best > 0; ++q)
              best = std::min(best, std::max(std::abs(p - q), int(d[base + std::size_t(q) * stride[ax]])));
            next[base + std::size_t(p) * stride[ax]] = std::uint8_t(best);
          }
        }
    });
    d.swap(next);
  }
  return d;
}

/// reach (see Macrocells) from the live flags: the distance to the nearest macrocell of the other
/// state, minus one.
void build_reach(Macrocells& m) {
  constexpr int cap = Macrocells::kMaxReach + 1;
  std::vector<std::uint8_t> dead(m.live.size());
  for (std::size_t c = 0; c < dead.size(); ++c) dead[c] = m.live[c] ? 0 : 1;
  const auto to_dead = chebyshev_distance(dead, m.bx, m.by, m.bz, cap);
  const auto to_live = chebyshev_distance(m.live, m.bx, m.by, m.bz, cap);
  m.reach.resize(m.live.size());
  for (std::size_t c = 0; c < m.live.size(); ++c) m.reach[c] = std::uint8_t((m.live[c] ? to_dead[c] : to_live[c]) - 1);
}

Macrocells build_macrocells(const Volume& v) {
  Macrocells m;
  constexpr int B = Macrocells::kB;
  m.bx = (v.nx() + B - 1) / B;
  m.by = (v.ny() + B - 1) / B;
  m.bz = (v.nz() + B - 1) / B;
  m.live.assign(std::size_t(m.bx) * std::size_t(m.by) * std::size_t(m.bz), 0);
  visit_samples(v, [&](const auto& s) {
    // Per macrocell, the samples [cB - 1, (c + 1)B + 1] per axis (clamped), until one is > 0.
    tbb::parallel_for(tbb::blocked_range<int>(0, m.bz), [&](const tbb::blocked_range<int>& r) {
      for (int cz = r.begin(); cz < r.end(); ++cz)
        for (int cy = 0; cy < m.by; ++cy)
          for (int cx = 0; cx < m.bx; ++cx) {
            const int i0 = std::max(0, cx * B - 1), i1 = std::min(v.nx() - 1, (cx + 1) * B + 1);
            const int j0 = std::max(0, cy * B - 1), j1 = std::min(v.ny() - 1, (cy + 1) * B + 1);
            const int k0 = std::max(0, cz * B - 1), k1 = std::min(v.nz() - 1, (cz + 1) * B + 1);
            bool live = false;
            for (int k = k0; k <= k1 && !live; ++k)
              for (int j = j0; j <= j1 && !live; ++j)
                for (int i = i0; i <= i1; ++i)
                  if (s.at(i, j, k) > 0.0f) {
                    live = true;
                    break;
                  }
            m.live[m.index(cx, cy, cz)] = live ? 1 : 0;
          }
    });
    return 0;
  });
  build_reach(m);
  return m;
}

/// A located sample: the lower corner of its trilinear stencil and the weights (a shadow cache on
/// the volume's grid is read with the same stencil).
struct Cell {
  int ix, iy, iz;
  float tx, ty, tz;
};

/// One light as the kernel sees it.
struct LightTerm {
  LightType type = LightType::kPoint;
  Vec3 position = Vec3::Zero(), to_light = Vec3::UnitZ();
  Rgb intensity = Rgb::Ones();
  bool inverse_square = false;
  const VolumeSamples<float>* cache = nullptr;  // shadow cache (HGAttenuated, kCache)
  Vec3 cache_origin = Vec3::Zero(), cache_inv_spacing = Vec3::Ones();
  bool cache_same_grid = false;
};

/// The samples of a march along o + t d (unit d), t = t0 + (i + φ) h for i < n (the equal-step
/// grid of a shadow march or a kFitSegment ray) or t0 + φ h + i h while < t1 (the primary grid of
/// kDiagonalOverN), with empty macrocells skipped on the same grid.
template <class T>
class Sampler {
 public:
  Sampler(const VolumeSamples<T>& s, const Volume& v, const Macrocells& m, VolumeAddress address)
      : s_(s), m_(m), wrap_(address == VolumeAddress::kWrap) {
    origin_ = v.origin();
    inv_spacing_ = v.spacing().cwiseInverse();
    n_[0] = v.nx();
    n_[1] = v.ny();
    n_[2] = v.nz();
  }

  /// The trilinear value at index coordinates g.
  float value(double gx, double gy, double gz) const {
    return wrap_ ? s_.trilinear_wrapped(float(gx), float(gy), float(gz))
                 : s_.trilinear_clamped(float(gx), float(gy), float(gz));
  }

  /// Calls fn(i, g, f) for the samples i = i_begin .. i_end-1 at t_i = a + i h (a the first
  /// sample's t) that are not known to be empty: g the index coordinates, f the value (> 0 or
  /// not: callers test). fn returns false to stop. Returns the number of samples skipped.
  template <class Fn>
  std::int64_t march(const Vec3& o, const Vec3& d, double a, double h, std::int64_t i_end, const Fn& fn) const {
    const Vec3 go = (o - origin_).cwiseProduct(inv_spacing_);
    const Vec3 gd = d.cwiseProduct(inv_spacing_);
    const bool skip = m_.enabled() && !wrap_;
    const double g0[3] = {go.x(), go.y(), go.z()}, gv[3] = {gd.x(), gd.y(), gd.z()};
    const double inv_gv[3] = {1.0 / gv[0], 1.0 / gv[1], 1.0 / gv[2]};
    std::int64_t skipped = 0;
    constexpr int B = Macrocells::kB;
    const int nb[3] = {m_.bx, m_.by, m_.bz};
    // The first sample at or beyond where the ray leaves macrocell c (along t): a dead macrocell is
    // empty one sample beyond its faces, so the rounding of the exit does not matter; a live one's
    // run may end a sample early or late, which only means that sample is located again.
    // With reach r: where it leaves the cube of macrocells c ± r, all of c's state.
    auto next_after_exit = [&](const int c[3], int r, std::int64_t i) {
      double t_exit = kInf;
      for (int ax = 0; ax < 3; ++ax) {
        if (gv[ax] > 0.0) {
          if (c[ax] + r + 1 < nb[ax]) t_exit = std::min(t_exit, ((c[ax] + r + 1) * B - g0[ax]) * inv_gv[ax]);
        } else if (gv[ax] < 0.0) {
          if (c[ax] - r > 0) t_exit = std::min(t_exit, ((c[ax] - r) * B - g0[ax]) * inv_gv[ax]);
        }
      }
      const double q = std::ceil((t_exit - a) / h);
      return q >= double(i_end) ? i_end : std::max(i + 1, static_cast<std::int64_t>(std::max(q, 0.0)));
    };
    for (std::int64_t i = 0; i < i_end;) {
      std::int64_t run_end = i_end;
      if (skip) {
        const double t = a + double(i) * h;
        const int c[3] = {std::clamp(int(std::floor(g0[0] + t * gv[0])), 0, n_[0] - 1) / B,
                          std::clamp(int(std::floor(g0[1] + t * gv[1])), 0, n_[1] - 1) / B,
                          std::clamp(int(std::floor(g0[2] + t * gv[2])), 0, n_[2] - 1) / B};
        const std::size_t ci = m_.index(c[0], c[1], c[2]);
        run_end = next_after_exit(c, m_.reach[ci], i);
        if (!m_.live[ci]) {
          skipped += run_end - i;
          i = run_end;
          continue;
        }
      }
      // A live run: every sample located and sampled, no further tests.
      for (; i < run_end; ++i) {
        const double t = a + double(i) * h;
        const double gx = g0[0] + t * gv[0], gy = g0[1] + t * gv[1], gz = g0[2] + t * gv[2];
        const double fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
        const Cell cell{int(fx), int(fy), int(fz), float(gx - fx), float(gy - fy), float(gz - fz)};
        const float f = wrap_ ? s_.trilinear_wrapped(float(gx), float(gy), float(gz))
                              : s_.trilinear_cell(cell.ix, cell.iy, cell.iz, cell.tx, cell.ty, cell.tz);
        if (!fn(i, gx, gy, gz, f, cell)) return skipped;
      }
    }
    return skipped;
  }

 private:
  VolumeSamples<T> s_;
  const Macrocells& m_;
  bool wrap_;
  Vec3 origin_, inv_spacing_;
  int n_[3];
};

/// Everything a render needs that does not change from pixel to pixel.
template <class S>
struct Kernel {
  const Volume& volume;
  const VolumeRenderSettings& s;
  Box3 box;
  double ds = 0;        // primary step (kDiagonalOverN) or the largest step (kFitSegment)
  double shadow_h = 0;  // shadow step
  Macrocells macro;
  Sampler<S> sampler;
  std::vector<LightTerm> lights;
  std::vector<VolumeSamples<float>> cache_samples;
  Vec3 centre;
  double rim_radius = 1;
  bool all_cached_same_grid = false;  // every light's shadow comes from a cache on the volume's grid

  Kernel(const Volume& v, const VolumeRenderSettings& settings, const VolumeSamples<S>& samples, Macrocells m)
      : volume(v), s(settings), box(v.domain()), macro(std::move(m)), sampler(samples, v, macro, settings.address) {
    ds = primary_step(v, settings);
    shadow_h = settings.shadow_step > 0 ? settings.shadow_step : ds;
    centre = box.centre();
    rim_radius = 0.5 * box.size().minCoeff();
  }

  double extinction_weight(float f) const { return s.gamma == 1.0 ? double(f) : std::pow(double(f), s.gamma); }

  /// κ ∫ f^γ from x along unit direction dir to the box exit (or max_distance if nearer),
  /// midpoint-rule sub-steps of equal length <= the shadow step, starting at the start offset.
  double optical_depth(const Vec3& x, const Vec3& dir, double max_distance, std::int64_t& samples) const {
    const auto hit = intersect_box(box, x, dir);
    if (!hit) return 0.0;
    const double end = std::min(max_distance, hit->t1);
    const double start = std::max(0.0, hit->t0);
    if (!(end > start)) return 0.0;
    const std::int64_t m = std::max<std::int64_t>(1, std::int64_t(std::ceil((end - start) / shadow_h)));
    const double h = (end - start) / double(m);
    double sum = 0;
    std::int64_t taken = 0;
    sampler.march(x, dir, start + s.shadow_start_offset * h, h, m,
                  [&](std::int64_t, double, double, double, float f, const Cell&) {
                    ++taken;
                    if (f > 0.0f) sum += extinction_weight(f);
                    return true;
                  });
    samples += taken;
    return s.kappa * h * sum;
  }

  /// The optical depth from x to light l (to the box exit, or the light if nearer).
  double shadow_optical_depth(const Vec3& x, const LightTerm& l, std::int64_t& samples) const {
    if (l.type == LightType::kDirectional) return optical_depth(x, l.to_light, kInf, samples);
    Vec3 dir = l.position - x;
    const double dist = dir.norm();
    if (!(dist > 0)) return 0.0;
    return optical_depth(x, dir / dist, dist, samples);
  }

  Rgb emission_colour(const Vec3& x) const {
    if (s.emission_field == EmissionField::kConstant) return s.emission;
    const double r = std::clamp((x - centre).norm() / rim_radius, 0.0, 1.0);
    return s.emission * (1.0 - r) + s.emission_rim * r;
  }

  /// One ray o + t v (unit v), its samples on [t0, t1]. Adds the radiance to I and returns T.
  /// Dispatches once per ray to the loop compiled for the model and the quadrature.
  double trace(const Vec3& o, const Vec3& v, double t0, double t1, std::uint64_t pixel_id, Rgb& I,
               VolumeRenderStats& st) const {
    switch (s.model) {
      case OpticalModel::kAbsorption:
        return trace_quad<OpticalModel::kAbsorption>(o, v, t0, t1, pixel_id, I, st);
      case OpticalModel::kEmission:
        return trace_quad<OpticalModel::kEmission>(o, v, t0, t1, pixel_id, I, st);
      case OpticalModel::kEmissionAbsorption:
        return trace_quad<OpticalModel::kEmissionAbsorption>(o, v, t0, t1, pixel_id, I, st);
      case OpticalModel::kHG:
        return trace_quad<OpticalModel::kHG>(o, v, t0, t1, pixel_id, I, st);
      case OpticalModel::kHGAttenuated:
        return trace_quad<OpticalModel::kHGAttenuated>(o, v, t0, t1, pixel_id, I, st);
      case OpticalModel::kTransferFunction:  // its own state (volume_tf.cpp)
        break;
    }
    return 1.0;
  }

  template <OpticalModel M>
  double trace_quad(const Vec3& o, const Vec3& v, double t0, double t1, std::uint64_t pixel_id, Rgb& I,
                    VolumeRenderStats& st) const {
    switch (s.quadrature) {
      case Quadrature::kInclusive:
        return trace_with<M, Quadrature::kInclusive>(o, v, t0, t1, pixel_id, I, st);
      case Quadrature::kExclusive:
        return trace_with<M, Quadrature::kExclusive>(o, v, t0, t1, pixel_id, I, st);
      case Quadrature::kExponential:
        return trace_with<M, Quadrature::kExponential>(o, v, t0, t1, pixel_id, I, st);
    }
    return 1.0;
  }

  template <OpticalModel M, Quadrature Q>
  double trace_with(const Vec3& o, const Vec3& v, double t0, double t1, std::uint64_t pixel_id, Rgb& I,
                    VolumeRenderStats& st) const {
    constexpr bool extinct = M != OpticalModel::kEmission;
    constexpr bool emits = M != OpticalModel::kAbsorption;
    constexpr bool scatter = M == OpticalModel::kHG || M == OpticalModel::kHGAttenuated;
    constexpr bool attenuated = M == OpticalModel::kHGAttenuated;
    const SampleGrid grid = detail::sample_grid(s, ds, t0, t1, pixel_id);
    const double h = grid.h, a = grid.a;
    const std::int64_t n_max = grid.n;
    const double kappa_h = s.kappa * h;
    const double source_step = s.emission_scale_by_ds ? h : 1.0;
    const double emission_k = s.kappa_in_source ? s.kappa : 1.0;
    const double scatter_k = s.albedo * (s.kappa_in_brdf ? s.kappa : 1.0);
    const bool need_x = s.emission_field != EmissionField::kConstant || (attenuated && !all_cached_same_grid);
    const bool partial = s.include_last_partial && s.step_rule == StepRule::kDiagonalOverN;
    // Per light and ray: a directional light's phase is constant along the ray; a point light's
    // depends on t only: with r² = |x - L|² = qa + 2 qb t + t² and (x - L)·v = qb + t, cos θ =
    // (x - L)/r · (-v) = -(qb + t)/r. Its phase (and falloff) is evaluated for blocks of
    // kChunk consecutive samples at once (a loop the compiler vectorises), when first needed.
    constexpr int kChunk = 16;
    const std::size_t nl = scatter ? lights.size() : 0;
    double phase_const[kMaxLights], qa[kMaxLights], qb[kMaxLights];
    double phase[kMaxLights][kChunk];
    bool any_point = false;
    std::int64_t chunk = -kChunk - 1;
    const double c = s.hg_c, hg_k = (1 - c * c) / (4 * std::numbers::pi), hg_1c2 = 1 + c * c;
    for (std::size_t l = 0; l < nl; ++l) {
      if (lights[l].type == LightType::kDirectional) {
        phase_const[l] = henyey_greenstein(lights[l].to_light.dot(v), c);
      } else {
        const Vec3 d = o - lights[l].position;
        qa[l] = d.squaredNorm();
        qb[l] = d.dot(v);
        any_point = true;
      }
    }
    auto fill_chunk = [&](std::int64_t first) {
      for (std::size_t l = 0; l < nl; ++l) {
        if (lights[l].type == LightType::kDirectional) continue;
        const bool inv2 = lights[l].inverse_square;
        const double A = qa[l], B = qb[l];
        double* out = phase[l];
        for (int j = 0; j < kChunk; ++j) {
          const double t = a + double(first + j) * h;
          const double r2 = A + t * (2 * B + t);
          const double r = std::sqrt(r2);
          const double cos_theta = -(B + t) / r;
          const double D = hg_1c2 - 2 * c * cos_theta;
          out[j] = hg_k / (D * std::sqrt(D)) * (inv2 ? 1.0 / r2 : 1.0);
        }
      }
    };

    // Radiance in three plain doubles: Eigen's small-vector loops were not inlined in this lambda.
    double Ir = 0, Ig = 0, Ib = 0;
    const double Er = s.emission.x(), Eg = s.emission.y(), Eb = s.emission.z();
    const double Ar = s.ambient.x(), Ag = s.ambient.y(), Ab = s.ambient.z();
    const bool has_ambient = Ar != 0 || Ag != 0 || Ab != 0;
    double T = 1.0, ext = 0.0;
    std::int64_t taken = 0;
    bool terminated = false;
    // The inclusive and exclusive quadratures defer the transmittance of the non-empty samples to
    // batches of kBatch: the optical depths are summed in order as before, then the exponentials of
    // a batch are taken in one loop the compiler vectorises (they were the longest chain of a
    // sample), then the batch is composited in order. Every value and every sum is the one the
    // per-sample loop computed, so the images are the same bit for bit; a ray that terminates
    // (ERT) mid-batch stops at the same sample and its counter is restored to that sample.
    constexpr bool batched = extinct && Q != Quadrature::kExponential;
    constexpr int kBatch = batched ? 16 : 1;
    int nb = 0;
    float tau_b[kBatch];    // -κ h Σe (inclusive) or -κ Σ e w (exclusive), per sample
    float T_b[kBatch];      // exp of it
    double step_b[kBatch];  // the sample's g_step
    double gr_b[kBatch], gg_b[kBatch], gb_b[kBatch];
    std::int64_t taken_b[kBatch];  // `taken` after the sample
    // Composites the batch in order; returns false (and stops) where the transmittance falls below
    // the ERT threshold.
    auto flush = [&]() {
      if constexpr (batched) {
        for (int j = 0; j < nb; ++j) T_b[j] = exp_nonpositive(tau_b[j]);
        for (int j = 0; j < nb; ++j) {
          const double Tj = double(T_b[j]);
          const double k = (Q == Quadrature::kInclusive ? Tj : T) * step_b[j];
          T = Tj;
          if constexpr (emits) Ir += gr_b[j] * k, Ig += gg_b[j] * k, Ib += gb_b[j] * k;
          if (T < s.ert_transmittance) {
            terminated = true;
            taken = taken_b[j];
            nb = 0;
            return false;
          }
        }
        nb = 0;
      }
      return true;
    };
    st.skipped += sampler.march(
        o, v, a, h, n_max, [&](std::int64_t i, double gx, double gy, double gz, float f, const Cell& cell) {
          ++taken;
          if (!(f > 0.0f)) return true;  // e = 0: nothing added, T unchanged (bit for bit)
          const double e = extinction_weight(f);
          // The step this sample stands for: h, or the part of the last step before t1.
          double w = h;
          if (partial && i + 1 == n_max) w = std::min(h, t1 - (a + double(i) * h));
          double gr = 0, gg = 0, gb = 0;
          if constexpr (emits) {
            Vec3 x = Vec3::Zero();
            if (need_x) x = volume.world_from_index(Vec3(gx, gy, gz));
            const double ke = emission_k * e;
            if (s.emission_field == EmissionField::kConstant) {
              gr = Er * ke, gg = Eg * ke, gb = Eb * ke;
            } else {
              const Rgb C = emission_colour(x);
              gr = C.x() * ke, gg = C.y() * ke, gb = C.z() * ke;
            }
            if constexpr (scatter) {
              if (any_point && (i < chunk || i >= chunk + kChunk)) {
                chunk = i;
                fill_chunk(chunk);
              }
              for (std::size_t l = 0; l < nl; ++l) {
                const LightTerm& L = lights[l];
                const double p = L.type == LightType::kDirectional ? phase_const[l] : phase[l][i - chunk];
                double Ts = 1.0;
                if constexpr (attenuated) {
                  if (L.cache && L.cache_same_grid) {
                    Ts = L.cache->trilinear_cell(cell.ix, cell.iy, cell.iz, cell.tx, cell.ty, cell.tz);
                  } else if (L.cache) {
                    const Vec3 gc = (x - L.cache_origin).cwiseProduct(L.cache_inv_spacing);
                    Ts = L.cache->trilinear_clamped(float(gc.x()), float(gc.y()), float(gc.z()));
                  } else {
                    Ts = std::exp(-shadow_optical_depth(x, L, st.shadow_samples));
                  }
                }
                const double k = scatter_k * e * p * Ts;
                gr += L.intensity.x() * k, gg += L.intensity.y() * k, gb += L.intensity.z() * k;
              }
              if (has_ambient) {  // the uniform ambient radiance, ∫ p dω = 1, unshadowed
                const double k = scatter_k * e;
                gr += Ar * k, gg += Ag * k, gb += Ab * k;
              }
            }
          }
          // The source's sum of g (no Δs, vlr.emission.scale_by_ds = false) counts a partial step in proportion.
          const double g_step = w == h ? source_step : source_step * (w / h);
          if constexpr (!extinct) {
            const double k = Q == Quadrature::kExponential ? w : g_step;
            Ir += gr * k, Ig += gg * k, Ib += gb * k;
            return true;
          } else if constexpr (batched) {
            // T = exp(-τ) from the optical depth τ summed in double, never a running product (which
            // would drift by the rounding of every factor); the exponentials in float (~1 ulp, 6e-8
            // relative, below the float sampling of the volume). Inclusive: the sample's own step
            // is in its T; exclusive: the sample is weighted by the T before it.
            if constexpr (Q == Quadrature::kInclusive) {
              ext += w == h ? e : e * (w / h);
              tau_b[nb] = float(-kappa_h * ext);
            } else {
              ext += e * w;
              tau_b[nb] = float(-s.kappa * ext);
            }
            step_b[nb] = g_step;
            gr_b[nb] = gr, gg_b[nb] = gg, gb_b[nb] = gb;
            taken_b[nb] = taken;
            return ++nb < kBatch || flush();
          } else {
            // The exponential quadrature: 1 - e^{-x} as -expm1 so a thin step keeps its digits.
            const double sigma = s.kappa * e;
            const double k = T * (sigma > 0 ? double(-std::expm1(float(-sigma * w))) / sigma : w);
            ext += e * w;
            T = double(exp_nonpositive(float(-s.kappa * ext)));
            if constexpr (emits) Ir += gr * k, Ig += gg * k, Ib += gb * k;
            if (T < s.ert_transmittance) {
              terminated = true;
              return false;
            }
            return true;
          }
        });
    if (nb > 0) flush();
    I += Rgb(Ir, Ig, Ib);
    st.samples += taken;
    if (terminated) ++st.terminated;
    return extinct ? T : 1.0;
  }
};

template <class Fn>
void for_tiles(int width, int height, bool parallel, const Fn& fn) {
  constexpr int kTile = 16;
  if (parallel) {
    tbb::parallel_for(tbb::blocked_range2d<int>(0, height, kTile, 0, width, kTile),
                      [&](const tbb::blocked_range2d<int>& r) {
                        fn(r.rows().begin(), r.rows().end(), r.cols().begin(), r.cols().end());
                      });
  } else {
    fn(0, height, 0, width);
  }
}

void add_stats(VolumeRenderStats& a, const VolumeRenderStats& b) {
  a.rays += b.rays;
  a.samples += b.samples;
  a.skipped += b.skipped;
  a.shadow_samples += b.shadow_samples;
  a.terminated += b.terminated;
  a.silhouette_mismatch += b.silhouette_mismatch;
}

std::vector<LightTerm> light_terms(const Volume& v, const VolumeRenderSettings& s) {
  std::vector<LightTerm> out;
  for (const auto& l : effective_lights(v, s)) {
    LightTerm t;
    t.type = l.type;
    t.position = l.position;
    t.to_light = l.to_light.normalized();
    t.intensity = l.intensity;
    t.inverse_square = l.type == LightType::kPoint && l.falloff == LightFalloff::kInverseSquare;
    out.push_back(t);
  }
  if (out.size() > kMaxLights) throw InputError(fmt::format("volume render: at most {} lights", kMaxLights));
  return out;
}

/// The cache's grid: the volume's grid, or `scale` times as many samples per axis over the same
/// domain.
Volume cache_grid(const Volume& v, double scale) {
  if (scale == 1.0) {
    Volume c = Volume::allocate(v.nx(), v.ny(), v.nz(), SampleType::kFloat32, "shadow cache");
    c.set_placement(v.placement());
    c.set_origin(v.origin());
    c.set_spacing(v.spacing());
    c.set_value_scale(1.0);
    return c;
  }
  auto dim = [&](int n) {
    return std::max(v.placement() == SamplePlacement::kNodes ? 2 : 1, int(std::lround(n * scale)));
  };
  Volume c = Volume::allocate(dim(v.nx()), dim(v.ny()), dim(v.nz()), SampleType::kFloat32, "shadow cache");
  c.set_placement(v.placement());
  c.fit_to_box(v.domain());
  c.set_value_scale(1.0);
  return c;
}

template <class S>
void build_cache_march(const Kernel<S>& k, const LightTerm& l, Volume& cache, VolumeRenderStats& st, bool parallel) {
  auto* out = static_cast<float*>(cache.mutable_data());
  tbb::combinable<std::int64_t> samples([] { return std::int64_t{0}; });
  auto slab = [&](int k0, int k1) {
    std::int64_t& n = samples.local();
    for (int kk = k0; kk < k1; ++kk)
      for (int j = 0; j < cache.ny(); ++j)
        for (int i = 0; i < cache.nx(); ++i) {
          const Vec3 x = cache.world_from_index(Vec3(i, j, kk));
          out[std::size_t(i) + std::size_t(cache.nx()) * (std::size_t(j) + std::size_t(cache.ny()) * std::size_t(kk))] =
              float(std::exp(-k.shadow_optical_depth(x, l, n)));
        }
  };
  if (parallel)
    tbb::parallel_for(tbb::blocked_range<int>(0, cache.nz()),
                      [&](const tbb::blocked_range<int>& r) { slab(r.begin(), r.end()); });
  else
    slab(0, cache.nz());
  st.shadow_samples += samples.combine(std::plus<>());
}

/// The sweep: the cache's samples are visited layer by layer along the axis `ax` on which the
/// light lies beyond the box (for a directional light, its dominant axis), starting with the layer
/// nearest the light. A sample x of layer q looks up T at the point where its ray to the light
/// crosses layer q - 1 (bilinearly in that layer, whose values are final) and multiplies by the
/// transmittance of the segment between (Simpson's rule on f^γ at x, the midpoint and the crossing,
/// the crossing's f bilinear in the layer). Samples whose crossing falls outside the layer, and the
/// first layer, are marched exactly. O(samples) instead of O(samples · m).
template <class S>
bool build_cache_sweep(const Kernel<S>& k, const LightTerm& l, Volume& cache, VolumeRenderStats& st, bool parallel) {
  const Box3 box = k.box;
  int ax = -1;
  double sign = 0;
  if (l.type == LightType::kDirectional) {
    l.to_light.cwiseAbs().maxCoeff(&ax);
    sign = l.to_light[ax] > 0 ? 1.0 : -1.0;
  } else {
    // The axis on which the light is farthest beyond the box, relative to the box's size.
    double best = 0;
    for (int a = 0; a < 3; ++a) {
      const double beyond_hi = (l.position[a] - box.hi[a]) / box.size()[a];
      const double beyond_lo = (box.lo[a] - l.position[a]) / box.size()[a];
      if (beyond_hi > best) best = beyond_hi, ax = a, sign = 1.0;
      if (beyond_lo > best) best = beyond_lo, ax = a, sign = -1.0;
    }
    if (ax < 0) return false;  // the light is within the box's slab on every axis: march
  }
  const int n[3] = {cache.nx(), cache.ny(), cache.nz()};
  const int u = (ax + 1) % 3, w = (ax + 2) % 3;  // the layer's axes
  const Vec3 spacing = cache.spacing();
  auto* out = static_cast<float*>(cache.mutable_data());
  const std::int64_t stride[3] = {1, n[0], std::int64_t(n[0]) * n[1]};
  // Field value f^γ at cache sample (i, j, k) through the volume's sampler (the cache may be finer).
  tbb::combinable<std::int64_t> marched([] { return std::int64_t{0}; });
  auto e_at = [&](const Vec3& x) {
    const Vec3 g = k.volume.index_from_world(x);
    const float f = k.sampler.value(g.x(), g.y(), g.z());
    return f > 0 ? k.extinction_weight(f) : 0.0;
  };
  const int first = sign > 0 ? n[ax] - 1 : 0, step = sign > 0 ? -1 : 1;
  for (int q = first; q >= 0 && q < n[ax]; q += step) {
    auto row = [&](int b0, int b1) {
      std::int64_t& counter = marched.local();
      for (int b = b0; b < b1; ++b)
        for (int a = 0; a < n[u]; ++a) {
          int idx[3];
          idx[ax] = q;
          idx[u] = a;
          idx[w] = b;
          const Vec3 x = cache.world_from_index(Vec3(idx[0], idx[1], idx[2]));
          const std::int64_t o = idx[0] * stride[0] + idx[1] * stride[1] + idx[2] * stride[2];
          Vec3 dir = l.type == LightType::kDirectional ? l.to_light : (l.position - x).normalized();
          bool done = false;
          if (q != first && dir[ax] * sign > 0) {
            const double len = spacing[ax] / std::abs(dir[ax]);
            const Vec3 y = x + len * dir;  // on layer q - step
            const Vec3 gy = cache.index_from_world(y);
            const double gu = gy[u], gw = gy[w];
            if (gu >= 0 && gw >= 0 && gu <= n[u] - 1 && gw <= n[w] - 1) {
              const int u0 = std::min(int(gu), n[u] - 1), w0 = std::min(int(gw), n[w] - 1);
              const int u1 = std::min(u0 + 1, n[u] - 1), w1 = std::min(w0 + 1, n[w] - 1);
              const double tu = gu - u0, tw = gw - w0;
              auto Tc = [&](int aa, int bb) {
                int id[3];
                id[ax] = q - step;
                id[u] = aa;
                id[w] = bb;
                return double(out[id[0] * stride[0] + id[1] * stride[1] + id[2] * stride[2]]);
              };
              const double Ty =
                  (Tc(u0, w0) * (1 - tu) + Tc(u1, w0) * tu) * (1 - tw) + (Tc(u0, w1) * (1 - tu) + Tc(u1, w1) * tu) * tw;
              const double tau = k.s.kappa * len * (e_at(x) + 4.0 * e_at(x + 0.5 * len * dir) + e_at(y)) / 6.0;
              out[o] = float(Ty * std::exp(-tau));
              done = true;
            }
          }
          if (!done) out[o] = float(std::exp(-k.shadow_optical_depth(x, l, counter)));
        }
    };
    if (parallel)
      tbb::parallel_for(tbb::blocked_range<int>(0, n[w]),
                        [&](const tbb::blocked_range<int>& r) { row(r.begin(), r.end()); });
    else
      row(0, n[w]);
  }
  st.shadow_samples += marched.combine(std::plus<>());
  return true;
}

template <class S>
ShadowCache build_cache_impl(const Kernel<S>& k, const LightTerm& l, const VolumeRenderSettings& s,
                             VolumeRenderStats& st) {
  ShadowCache c;
  c.transmittance = cache_grid(k.volume, s.shadow_cache_scale);
  if (s.shadow_cache_build == ShadowCacheBuild::kSweep && build_cache_sweep(k, l, c.transmittance, st, s.parallel))
    return c;
  build_cache_march(k, l, c.transmittance, st, s.parallel);
  return c;
}

/// The state of seed 000's models: the volume and the settings it owns (the kernel refers to them),
/// the kernel, and the shadow caches.
template <class S>
struct TypedTracerState final : TracerState {
  Volume volume;
  VolumeRenderSettings settings;
  std::vector<ShadowCache> caches;
  Kernel<S> k;

  TypedTracerState(const Volume& v, const VolumeRenderSettings& s, const std::vector<ShadowCache>& given)
      : volume(v), settings(s), k(volume, settings, volume.samples<S>(), macrocells_for(volume, settings)) {
    box = k.box;
    k.lights = light_terms(volume, settings);
    if (settings.model != OpticalModel::kHGAttenuated || settings.shadow != ShadowMethod::kCache) return;
    if (given.size() == k.lights.size()) {
      caches = given;
    } else {
      const auto t = std::chrono::steady_clock::now();
      VolumeRenderStats st;
      for (const auto& l : k.lights) caches.push_back(build_cache_impl(k, l, settings, st));
      cache_ms = ms_since(t);
      cache_samples = st.shadow_samples;
    }
    k.cache_samples.reserve(caches.size());
    for (const auto& c : caches) {
      if (c.transmittance.type() != SampleType::kFloat32)
        throw InputError("volume render: a shadow cache must be float32");
      k.cache_samples.push_back(c.transmittance.samples<float>());
    }
    for (std::size_t i = 0; i < k.lights.size(); ++i) {
      const Volume& c = caches[i].transmittance;
      k.lights[i].cache = &k.cache_samples[i];
      k.lights[i].cache_origin = c.origin();
      k.lights[i].cache_inv_spacing = c.spacing().cwiseInverse();
      k.lights[i].cache_same_grid =
          c.dims() == volume.dims() && c.origin() == volume.origin() && c.spacing() == volume.spacing();
    }
    k.all_cached_same_grid =
        std::all_of(k.lights.begin(), k.lights.end(), [](const LightTerm& l) { return l.cache_same_grid; });
  }
  static Macrocells macrocells_for(const Volume& v, const VolumeRenderSettings& s) {
    return s.skip_empty && s.address == VolumeAddress::kClamp ? build_macrocells(v) : Macrocells{};
  }
  double trace(const Vec3& o, const Vec3& v, double t0, double t1, std::uint64_t pixel, Rgb& I,
               VolumeRenderStats& st) const override {
    return k.trace(o, v, t0, t1, pixel, I, st);
  }
  double optical_depth(const Vec3& x, const Vec3& d, double max_distance, std::int64_t& samples) const override {
    return k.optical_depth(x, d, max_distance, samples);
  }
};

}  // namespace

void check_volume_render_settings(const Volume& volume, const VolumeRenderSettings& settings) {
  validate(volume, settings);
  (void)light_terms(volume, settings);
}

double henyey_greenstein(double cos_theta, double c) {
  const double denom = 1.0 + c * c - 2.0 * c * cos_theta;
  return (1.0 - c * c) / (4.0 * std::numbers::pi * denom * std::sqrt(denom));
}

VolumeLight default_light(const Box3& box) {
  VolumeLight l;
  l.type = LightType::kPoint;
  l.position = box.centre() + 2.0 * box.size();
  return l;
}

std::optional<RayInterval> intersect_box(const Box3& box, const Vec3& o, const Vec3& v) {
  double t0 = -kInf, t1 = kInf;
  for (int a = 0; a < 3; ++a) {
    if (v[a] == 0.0) {
      if (o[a] < box.lo[a] || o[a] > box.hi[a]) return std::nullopt;
      continue;
    }
    double tn = (box.lo[a] - o[a]) / v[a], tf = (box.hi[a] - o[a]) / v[a];
    if (tn > tf) std::swap(tn, tf);  // vlr.slab.swap
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
  }
  if (t0 > t1 || t1 < 0) return std::nullopt;
  return RayInterval{t0, t1};
}

double primary_step(const Volume& volume, const VolumeRenderSettings& s) {
  if (s.step_rule == StepRule::kFitSegment || s.step_rule == StepRule::kFixedStep) return s.step;
  return volume.domain().diagonal() / s.samples;
}

SampleGrid detail::sample_grid(const VolumeRenderSettings& s, double ds, double t0, double t1, std::uint64_t pixel_id) {
  SampleGrid g;
  double h = ds;
  std::int64_t n_max;
  double offset_fraction = 0;
  switch (s.first_offset) {
    case FirstOffset::kZero:
      offset_fraction = 0;
      break;
    case FirstOffset::kHalf:
      offset_fraction = 0.5;
      break;
    case FirstOffset::kJitter:
      offset_fraction = unit_from_bits(splitmix64(s.jitter_seed ^ splitmix64(pixel_id)));
      break;
  }
  const double length = t1 - t0;
  if (s.step_rule == StepRule::kFitSegment) {
    n_max = std::max<std::int64_t>(1, std::int64_t(std::ceil(length / ds)));
    h = length / double(n_max);
  } else if (s.step_rule == StepRule::kFixedStep) {
    // Seed 001: floor(length / s) whole steps from the entry, each sampled φ of the way in.
    const double q = std::floor(length / h);
    n_max = q > 0 ? std::int64_t(q) : 0;
  } else {
    // Samples t0 + (φ + i) h < t1.
    const double q = (length / h) - offset_fraction;
    n_max = q > 0 ? std::int64_t(std::ceil(q)) : 0;
  }
  g.a = t0 + offset_fraction * h;
  g.h = h;
  g.n = n_max;
  return g;
}

std::vector<VolumeLight> effective_lights(const Volume& volume, const VolumeRenderSettings& s) {
  if (!s.lights.empty()) return s.lights;
  return {default_light(volume.domain())};
}

// ---- the tracer -----------------------------------------------------------------------------------

struct VolumeTracer::Impl {
  std::unique_ptr<TracerState> state;
  VolumeRenderSettings settings;
};

VolumeTracer::VolumeTracer(const Volume& volume, const VolumeRenderSettings& settings,
                           const std::vector<ShadowCache>& caches)
    : impl_(std::make_unique<Impl>()) {
  validate(volume, settings);
  impl_->settings = settings;
  if (settings.model == OpticalModel::kTransferFunction) {
    impl_->state = detail::make_tf_state(volume, settings, nullptr);
    return;
  }
  impl_->state = visit_samples(volume, [&](const auto& samples) -> std::unique_ptr<TracerState> {
    using S = typename std::remove_cv_t<std::remove_pointer_t<decltype(samples.data)>>;
    return std::make_unique<TypedTracerState<S>>(volume, settings, caches);
  });
}

VolumeTracer::VolumeTracer(const Volume& volume, const VolumeRenderSettings& settings,
                           std::shared_ptr<const VolumeRangeIndex> ranges)
    : impl_(std::make_unique<Impl>()) {
  validate(volume, settings);
  impl_->settings = settings;
  if (settings.model != OpticalModel::kTransferFunction)
    throw InputError("volume render: a range index is for the transfer_function model");
  impl_->state = detail::make_tf_state(volume, settings, std::move(ranges));
}

VolumeTracer::VolumeTracer(const BrickedVolume& volume, const VolumeRenderSettings& settings,
                           std::shared_ptr<const VolumeRangeIndex> ranges)
    : impl_(std::make_unique<Impl>()) {
  check_volume_render_settings(volume, settings);
  impl_->settings = settings;
  impl_->state = detail::make_tf_state(volume, settings, std::move(ranges));
}

void check_volume_render_settings(const BrickedVolume& volume, const VolumeRenderSettings& s) {
  if (volume.empty()) throw InputError("volume render: the volume is empty");
  if (s.model != OpticalModel::kTransferFunction)
    throw InputError(fmt::format("volume render: a bricked volume renders the transfer_function model only (not {})",
                                 optical_model_name(s.model)));
  validate_settings(s);
  detail::validate_tf(s, true);
}

VolumeTracer::~VolumeTracer() = default;

VolumeTracer::Result VolumeTracer::trace(const Vec3& o, const Vec3& d, double t_max, std::uint64_t pixel_id,
                                         VolumeRenderStats* stats) const {
  Result r;
  const auto hit = intersect_box(impl_->state->box, o, d);
  if (!hit) return r;
  const double t0 = std::max(hit->t0, 0.0), t1 = std::min(hit->t1, t_max);
  if (!(t1 > t0)) return r;
  r.met = true;
  VolumeRenderStats local;
  VolumeRenderStats& st = stats ? *stats : local;
  ++st.rays;
  r.transmittance = impl_->state->trace(o, d, t0, t1, pixel_id, r.radiance, st);
  return r;
}

double VolumeTracer::transmittance(const Vec3& x, const Vec3& d, double max_distance, VolumeRenderStats* stats) const {
  std::int64_t n = 0;
  const double tau = impl_->state->optical_depth(x, d, max_distance, n);
  if (stats) stats->shadow_samples += n;
  return std::exp(-tau);
}

const Box3& VolumeTracer::box() const { return impl_->state->box; }
double VolumeTracer::cache_build_ms() const { return impl_->state->cache_ms; }
std::int64_t VolumeTracer::cache_shadow_samples() const { return impl_->state->cache_samples; }
double VolumeTracer::index_build_ms() const { return impl_->state->index_ms; }

VolumeFrame render_volume(const Volume& volume, const Camera& camera, const VolumeRenderSettings& settings) {
  return render_volume(volume, camera, settings, {});
}

VolumeFrame render_volume(const Volume& volume, const Camera& camera, const VolumeRenderSettings& s,
                          const std::vector<ShadowCache>& caches) {
  const VolumeTracer tracer(volume, s, caches);
  return tracer.render(camera);
}

VolumeFrame render_volume(const BrickedVolume& volume, const Camera& camera, const VolumeRenderSettings& s) {
  const VolumeTracer tracer(volume, s);
  return tracer.render(camera);
}

VolumeFrame VolumeTracer::render(const Camera& camera) const {
  const TracerState& k = *impl_->state;
  if (auto own = k.render(camera)) return std::move(*own);
  const VolumeRenderSettings& s = impl_->settings;
  VolumeFrame frame;
  frame.stats.shadow_cache_ms = k.cache_ms;
  frame.stats.shadow_samples = k.cache_samples;
  const int W = camera_width(camera), H = camera_height(camera);
  frame.radiance = ImageF(W, H, 3, 0.0f);
  frame.transmittance = ImageF(W, H, 1, 1.0f);
  const RayGenerator gen(camera);
  const Box3& box = k.box;
  TwoPassRays two_pass;
  if (s.ray_generation == RayGeneration::kTwoPass) two_pass = two_pass_rays(box, camera);
  // The eye inside the box.
  if (const auto* pin = std::get_if<Pinhole>(&camera)) {
    const Vec3 eye = pin->camera_from_world.inverse().translation();
    if (box.contains(eye) && s.camera_inside == CameraInside::kReject)
      throw InputError(
          "volume render: the camera is inside the volume's box (vlr.camera.inside: reject); move it out or set "
          "camera_inside: start_at_eye");
  }
  const auto t_render = std::chrono::steady_clock::now();
  tbb::combinable<VolumeRenderStats> stats;
  for_tiles(W, H, s.parallel, [&](int y0, int y1, int x0, int x1) {
    VolumeRenderStats& st = stats.local();
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        Vec3 o, v;
        double t0 = 0, t1 = 0;
        const std::size_t p = std::size_t(y) * std::size_t(W) + std::size_t(x);
        if (s.ray_generation == RayGeneration::kTwoPass) {
          if (two_pass.front[p] != two_pass.back[p]) ++st.silhouette_mismatch;
          if (!two_pass.front[p] || !two_pass.back[p]) continue;
          o = two_pass.entry[p];
          const Vec3 span = two_pass.exit[p] - two_pass.entry[p];
          t1 = span.norm();
          if (!(t1 > 0)) continue;
          v = span / t1;
        } else {
          const CameraRay ray = gen.generate_ray(x, y);
          if (!ray.ok) continue;
          const auto hit = intersect_box(box, ray.origin, ray.direction);
          if (!hit) continue;
          o = ray.origin;
          v = ray.direction;
          t0 = std::max(hit->t0, 0.0);
          t1 = hit->t1;
        }
        ++st.rays;
        Rgb I = Rgb::Zero();
        const double T = k.trace(o, v, t0, t1, p, I, st);
        float* rad = frame.radiance.row(y) + 3 * x;
        rad[0] = float(I[0]);
        rad[1] = float(I[1]);
        rad[2] = float(I[2]);
        frame.transmittance.at(x, y) = float(T);
      }
  });
  stats.combine_each([&](const VolumeRenderStats& st) { add_stats(frame.stats, st); });
  frame.stats.render_ms = ms_since(t_render);
  return frame;
}

namespace {

/// Calls fn(kernel, light) with a kernel for the volume and light `light_index` of the settings.
template <class Fn>
auto with_kernel(const Volume& volume, const VolumeRenderSettings& settings, int light_index, const Fn& fn) {
  validate(volume, settings);
  return visit_samples(volume, [&](const auto& samples) {
    Macrocells macro;
    if (settings.skip_empty && settings.address == VolumeAddress::kClamp) macro = build_macrocells(volume);
    Kernel k(volume, settings, samples, std::move(macro));
    const auto lights = light_terms(volume, settings);
    if (light_index < 0 || light_index >= int(lights.size()))
      throw InputError(fmt::format("volume render: no light {}", light_index));
    return fn(k, lights[std::size_t(light_index)]);
  });
}

}  // namespace

ShadowCache build_shadow_cache(const Volume& volume, const VolumeRenderSettings& settings, int light_index,
                               VolumeRenderStats* stats) {
  return with_kernel(volume, settings, light_index, [&](const auto& k, const LightTerm& l) {
    VolumeRenderStats st;
    auto c = build_cache_impl(k, l, settings, st);
    if (stats) add_stats(*stats, st);
    return c;
  });
}

double shadow_transmittance(const Volume& volume, const VolumeRenderSettings& settings, int light_index,
                            const Vec3& x) {
  return with_kernel(volume, settings, light_index, [&](const auto& k, const LightTerm& l) {
    std::int64_t n = 0;
    return std::exp(-k.shadow_optical_depth(x, l, n));
  });
}

ImageF composite_over(const VolumeFrame& frame, const Rgb& background) {
  ImageF out(frame.radiance.width(), frame.radiance.height(), 3);
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) {
      const float T = frame.transmittance.at(x, y);
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = frame.radiance.at(x, y, c) + T * float(background[c]);
    }
  return out;
}

ImageF composite_over(const VolumeFrame& frame, const ImageF& background) {
  if (background.width() != frame.radiance.width() || background.height() != frame.radiance.height() ||
      background.channels() < 3)
    throw InputError(fmt::format("volume render: the background image must be {}x{} with 3 channels",
                                 frame.radiance.width(), frame.radiance.height()));
  ImageF out(frame.radiance.width(), frame.radiance.height(), 3);
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) {
      const float T = frame.transmittance.at(x, y);
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = frame.radiance.at(x, y, c) + T * background.at(x, y, c);
    }
  return out;
}

std::string optical_model_name(OpticalModel m) {
  switch (m) {
    case OpticalModel::kAbsorption:
      return "absorption";
    case OpticalModel::kEmission:
      return "emission";
    case OpticalModel::kEmissionAbsorption:
      return "emission_absorption";
    case OpticalModel::kHG:
      return "hg";
    case OpticalModel::kHGAttenuated:
      return "hg_attenuated";
    case OpticalModel::kTransferFunction:
      return "transfer_function";
  }
  return "emission_absorption";
}

std::string ess_scheme_name(EmptySpaceScheme e) {
  return e == EmptySpaceScheme::kOneLevel ? "one_level" : "multi_level";
}

std::string traversal_name(Traversal t) { return t == Traversal::kObjectOrder ? "object_order" : "image_order"; }

std::string quadrature_name(Quadrature q) {
  switch (q) {
    case Quadrature::kInclusive:
      return "inclusive";
    case Quadrature::kExclusive:
      return "exclusive";
    case Quadrature::kExponential:
      return "exponential";
  }
  return "inclusive";
}

// ---- the two-pass method ------------------------------------------------------------------------

TwoPassRays two_pass_rays(const Box3& box, const Camera& camera) {
  TwoPassRays r;
  r.width = camera_width(camera);
  r.height = camera_height(camera);
  const std::size_t n = std::size_t(r.width) * std::size_t(r.height);
  r.entry.assign(n, Vec3::Zero());
  r.exit.assign(n, Vec3::Zero());
  r.front.assign(n, 0);
  r.back.assign(n, 0);
  std::vector<double> depth_front(n, kInf), depth_back(n, -kInf);
  const RayGenerator gen(camera);
  // The 8 corners and 12 triangles (two per face, counter-clockwise seen from outside).
  std::array<Vec3, 8> c;
  for (int i = 0; i < 8; ++i)
    c[std::size_t(i)] =
        Vec3(i & 1 ? box.hi.x() : box.lo.x(), i & 2 ? box.hi.y() : box.lo.y(), i & 4 ? box.hi.z() : box.lo.z());
  struct Face {
    int a, b, cc, d;  // corners, counter-clockwise from outside
    Vec3 normal;
  };
  const Face faces[6] = {{0, 4, 6, 2, -Vec3::UnitX()}, {1, 3, 7, 5, Vec3::UnitX()},  {0, 1, 5, 4, -Vec3::UnitY()},
                         {2, 6, 7, 3, Vec3::UnitY()},  {0, 2, 3, 1, -Vec3::UnitZ()}, {4, 5, 7, 6, Vec3::UnitZ()}};
  for (const Face& f : faces) {
    const int tris[2][3] = {{f.a, f.b, f.cc}, {f.a, f.cc, f.d}};
    const Vec3& on_plane = c[std::size_t(f.a)];
    for (const auto& tri : tris) {
      std::array<Projection, 3> pr;
      bool behind = false;
      for (int i = 0; i < 3; ++i) {
        pr[std::size_t(i)] = gen.project(c[std::size_t(tri[i])]);
        if (!pr[std::size_t(i)].in_front || !pr[std::size_t(i)].pixel.allFinite()) behind = true;
      }
      if (behind) continue;  // the source's proxy is in front of the camera; a clipped face is not drawn
      const Vec2d p0 = pr[0].pixel, p1 = pr[1].pixel, p2 = pr[2].pixel;
      const double area = (p1.x() - p0.x()) * (p2.y() - p0.y()) - (p1.y() - p0.y()) * (p2.x() - p0.x());
      if (area == 0.0) continue;
      // Facing from the eye: front when the outward normal points to the camera.
      const CameraRay centre_ray = gen.generate_ray(0.5 * (r.width - 1), 0.5 * (r.height - 1));
      const Vec3 eye = centre_ray.origin;
      const bool front = f.normal.dot(on_plane - eye) < 0;
      // Edge functions, oriented so that the inside is positive; the top-left rule decides pixels
      // exactly on an edge (the same rule for every triangle, as a GPU rasteriser).
      const double sgn = area > 0 ? 1.0 : -1.0;
      auto edge = [&](const Vec2d& a, const Vec2d& b, double x, double y) {
        return sgn * ((b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x()));
      };
      auto top_left = [&](const Vec2d& a, const Vec2d& b) {
        const Vec2d e = sgn > 0 ? b - a : a - b;
        return (e.y() == 0 && e.x() < 0) || e.y() > 0;  // image y grows downwards
      };
      const bool tl0 = top_left(p1, p2), tl1 = top_left(p2, p0), tl2 = top_left(p0, p1);
      const int xmin = std::max(0, int(std::ceil(std::min({p0.x(), p1.x(), p2.x()}))));
      const int xmax = std::min(r.width - 1, int(std::floor(std::max({p0.x(), p1.x(), p2.x()}))));
      const int ymin = std::max(0, int(std::ceil(std::min({p0.y(), p1.y(), p2.y()}))));
      const int ymax = std::min(r.height - 1, int(std::floor(std::max({p0.y(), p1.y(), p2.y()}))));
      for (int y = ymin; y <= ymax; ++y)
        for (int x = xmin; x <= xmax; ++x) {
          const double w0 = edge(p1, p2, x, y), w1 = edge(p2, p0, x, y), w2 = edge(p0, p1, x, y);
          if (w0 < 0 || w1 < 0 || w2 < 0) continue;
          if ((w0 == 0 && !tl0) || (w1 == 0 && !tl1) || (w2 == 0 && !tl2)) continue;
          const CameraRay ray = gen.generate_ray(x, y);
          const double denom = f.normal.dot(ray.direction);
          if (denom == 0.0) continue;
          const double t = f.normal.dot(on_plane - ray.origin) / denom;
          const Vec3 hit = ray.at(t);
          const std::size_t p = std::size_t(y) * std::size_t(r.width) + std::size_t(x);
          if (front) {
            if (t < depth_front[p]) depth_front[p] = t, r.entry[p] = hit, r.front[p] = 1;
          } else {
            if (t > depth_back[p]) depth_back[p] = t, r.exit[p] = hit, r.back[p] = 1;
          }
        }
    }
  }
  return r;
}

}  // namespace meltlab::render
