// Photo-like rendering of voxel ice on a textured ground (see integrator/ice_photo.h).

#include <meltlab/render/integrator/ice_photo.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::render {

using meltlab::Grid3;
using sim::physics::IceFraction;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- hashing (counter-based, no shared state) ------------------------------------------

inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
inline std::uint64_t hash3(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return splitmix64(splitmix64(splitmix64(a) ^ b) ^ c);
}
inline double to_unit(std::uint64_t h) {  // (0, 1)
  return (static_cast<double>(h >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// ---- ray / box ------------------------------------------------------------------------------

struct Box {
  Vec3d lo, hi;
  bool empty = true;
};

/// [t0, t1] of the ray o + t d inside the box (slab method, per-axis swap; vlr.slab.swap);
/// false on a miss. Axes with d = 0 require o inside the slab.
bool slab(const Box& b, const Vec3d& o, const Vec3d& d, double& t0, double& t1) {
  if (b.empty) return false;
  t0 = -kInf;
  t1 = kInf;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < b.lo[a] || o[a] > b.hi[a]) return false;
      continue;
    }
    double tn = (b.lo[a] - o[a]) / d[a], tf = (b.hi[a] - o[a]) / d[a];
    if (tn > tf) std::swap(tn, tf);
    t0 = std::max(t0, tn);
    t1 = std::min(t1, tf);
  }
  return t0 <= t1;
}

/// The box where the trilinear interpolant of `g` can reach `threshold` (> 0: values ≥ it;
/// a convex combination reaches it only within one cell of a cell that does), clipped to the grid.
template <class T>
Box support_box(const Grid3<T>& g, double threshold, bool strictly_positive) {
  int lo[3] = {g.nx, g.ny, g.nz}, hi[3] = {-1, -1, -1};
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const double v = g.at(i, j, k);
        if (strictly_positive ? v > 0.0 : v >= threshold) {
          lo[0] = std::min(lo[0], i), lo[1] = std::min(lo[1], j), lo[2] = std::min(lo[2], k);
          hi[0] = std::max(hi[0], i), hi[1] = std::max(hi[1], j), hi[2] = std::max(hi[2], k);
        }
      }
  Box b;
  if (hi[0] < 0) return b;
  const int n[3] = {g.nx, g.ny, g.nz};
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = g.origin_m[a] + g.h_m * std::max(0.0, lo[a] - 0.5);
    b.hi[a] = g.origin_m[a] + g.h_m * std::min(double(n[a]), hi[a] + 1.5);
  }
  b.empty = false;
  return b;
}

// ---- fast trilinear sampling and empty-space skipping ----------------------------------------

/// The trilinear stencil of a point in a cell-centred grid: the same arithmetic as
/// Grid3::sample (so the same value to the last bit), but the clamped indices are computed once
/// and can be reused for another grid of the same geometry (the light-transmittance grid).
struct Stencil {
  std::size_t x0, x1, y0, y1, z0, z1;  // clamped i, nx·j, nx·ny·k of the two corners per axis
  double tx, ty, tz;
};

struct GridGeometry {
  int nx = 0, ny = 0, nz = 0;
  double h = 0;
  Vec3d origin = Vec3d::Zero();

  template <class T>
  explicit GridGeometry(const Grid3<T>& g) : nx(g.nx), ny(g.ny), nz(g.nz), h(g.h_m), origin(g.origin_m) {}

  /// Grid coordinates g = (p - origin)/h - 1/2 (as Grid3::sample); false outside the grid.
  bool coords(const Vec3d& p, double& gx, double& gy, double& gz) const {
    gx = (p.x() - origin.x()) / h - 0.5;
    gy = (p.y() - origin.y()) / h - 0.5;
    gz = (p.z() - origin.z()) / h - 0.5;
    return !(gx < -0.5 || gy < -0.5 || gz < -0.5 || gx > nx - 0.5 || gy > ny - 0.5 || gz > nz - 0.5);
  }
  void stencil(double gx, double gy, double gz, Stencil& s) const {
    const double fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
    s.tx = gx - fx;
    s.ty = gy - fy;
    s.tz = gz - fz;
    const int i0 = static_cast<int>(fx), j0 = static_cast<int>(fy), k0 = static_cast<int>(fz);
    const std::size_t sx = 1, sy = std::size_t(nx), sz = std::size_t(nx) * std::size_t(ny);
    s.x0 = sx * std::size_t(std::clamp(i0, 0, nx - 1));
    s.x1 = sx * std::size_t(std::clamp(i0 + 1, 0, nx - 1));
    s.y0 = sy * std::size_t(std::clamp(j0, 0, ny - 1));
    s.y1 = sy * std::size_t(std::clamp(j0 + 1, 0, ny - 1));
    s.z0 = sz * std::size_t(std::clamp(k0, 0, nz - 1));
    s.z1 = sz * std::size_t(std::clamp(k0 + 1, 0, nz - 1));
  }
  /// Grid3::sample at a located point (same operations, same order).
  static double interpolate(const float* v, const Stencil& s) {
    auto at = [v](std::size_t a, std::size_t b, std::size_t c) { return static_cast<double>(v[a + b + c]); };
    const double tx = s.tx, ty = s.ty, tz = s.tz;
    const double c00 = at(s.x0, s.y0, s.z0) * (1 - tx) + at(s.x1, s.y0, s.z0) * tx;
    const double c10 = at(s.x0, s.y1, s.z0) * (1 - tx) + at(s.x1, s.y1, s.z0) * tx;
    const double c01 = at(s.x0, s.y0, s.z1) * (1 - tx) + at(s.x1, s.y0, s.z1) * tx;
    const double c11 = at(s.x0, s.y1, s.z1) * (1 - tx) + at(s.x1, s.y1, s.z1) * tx;
    return (c00 * (1 - ty) + c10 * ty) * (1 - tz) + (c01 * (1 - ty) + c11 * ty) * tz;
  }
};

/// Coarse occupancy of kBlock³-cell blocks: a block is marked when some cell within kDilate = 1
/// cell of it has f != 0. The trilinear stencil of a point reads the cells floor(c - ½) and
/// floor(c - ½) + 1 (c: its position in cell units), so f is exactly 0 at every point within half
/// a cell of an unmarked block (the margin absorbs rounding in locating points and skip distances,
/// ~1e-12 cell). Blocks on the grid border extend to infinity outwards (f is 0 outside the grid,
/// and the clamped reads within half a cell of its faces are border cells of that block).
struct Occupancy {
  static constexpr int kBlock = 4;
  static constexpr int kDilate = 1;
  int bx = 0, by = 0, bz = 0;
  std::vector<std::uint8_t> marked;  // empty: skipping disabled (every block counts as marked)

  Occupancy() = default;
  explicit Occupancy(const IceFraction& g) {
    bx = (g.nx + kBlock - 1) / kBlock;
    by = (g.ny + kBlock - 1) / kBlock;
    bz = (g.nz + kBlock - 1) / kBlock;
    marked.assign(std::size_t(bx) * std::size_t(by) * std::size_t(bz), 0);
    auto range = [](int c, int nb, int& b0, int& b1) {
      b0 = std::max(0, (c - kDilate) / kBlock);  // c - kDilate >= -1: integer division rounds to 0
      b1 = std::min(nb - 1, (c + kDilate) / kBlock);
    };
    const float* v = g.value.data();
    for (int k = 0; k < g.nz; ++k)
      for (int j = 0; j < g.ny; ++j) {
        const float* row = v + g.index(0, j, k);
        for (int i = 0; i < g.nx; ++i) {
          if (row[i] == 0.0f) continue;  // any non-zero value (even negative or NaN) marks
          int i0, i1, j0, j1, k0, k1;
          range(i, bx, i0, i1);
          range(j, by, j0, j1);
          range(k, bz, k0, k1);
          for (int c = k0; c <= k1; ++c)
            for (int b = j0; b <= j1; ++b)
              for (int a = i0; a <= i1; ++a)
                marked[std::size_t(a) + std::size_t(bx) * (std::size_t(b) + std::size_t(by) * std::size_t(c))] = 1;
        }
      }
  }
  bool enabled() const { return !marked.empty(); }
};

/// Per cell: 1 when a cell within one cell of it (3³ neighbourhood) is non-zero, i.e. when the
/// trilinear stencil of some point in the cell can read a non-zero value.
std::vector<std::uint8_t> dilated_nonzero(const IceFraction& g) {
  const std::size_t n = g.size(), sy = std::size_t(g.nx), sz = std::size_t(g.nx) * std::size_t(g.ny);
  std::vector<std::uint8_t> a(n), b(n);
  for (std::size_t c = 0; c < n; ++c) a[c] = g.value[c] != 0.0f;
  // Separable max over ±1 cell along x, y, z (ping-pong a → b → a → b).
  auto pass = [&](const std::vector<std::uint8_t>& in, std::vector<std::uint8_t>& out, std::size_t stride, int len) {
    for (std::size_t c = 0; c < n; ++c) {
      const int pos = int((c / stride) % std::size_t(len));
      std::uint8_t m = in[c];
      if (pos > 0) m |= in[c - stride];
      if (pos + 1 < len) m |= in[c + stride];
      out[c] = m;
    }
  };
  pass(a, b, 1, g.nx);
  pass(b, a, sy, g.ny);
  pass(a, b, sz, g.nz);
  return b;
}

// ---- ground texture ----------------------------------------------------------------------------

/// The lattice values of the last cell visited per octave: neighbouring pixels mostly share
/// them (the coarse octaves span many pixels), and recomputing a lattice value costs 3 hashes.
struct TextureCache {
  std::int64_t ix[4] = {0, 0, 0, 0}, iy[4] = {0, 0, 0, 0};
  double lat[4][4] = {};
  bool valid[4] = {false, false, false, false};
};

double ground_texture_impl(double x_m, double y_m, double scale_m, std::uint64_t seed, TextureCache& cache) {
  if (!(scale_m > 0.0)) return 0.0;
  // fBm of value noise: 4 octaves, lacunarity 2, gain 0.5, quintic fade; in [-1, 1].
  double sum = 0, norm = 0, amp = 1, freq = 1.0 / scale_m;
  for (int oct = 0; oct < 4; ++oct) {
    const double x = x_m * freq, y = y_m * freq;
    const double fx = std::floor(x), fy = std::floor(y);
    const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
    auto fade = [](double t) { return t * t * t * (t * (t * 6 - 15) + 10); };
    const double tx = fade(x - fx), ty = fade(y - fy);
    auto lat = [&](std::int64_t a, std::int64_t b) {
      return 2.0 * to_unit(hash3(seed * 8 + std::uint64_t(oct), std::uint64_t(a), std::uint64_t(b))) - 1.0;
    };
    double* l = cache.lat[oct];
    if (cache.valid[oct] && cache.iy[oct] == iy && cache.ix[oct] + 1 == ix) {  // the next cell along x
      l[0] = l[1];
      l[2] = l[3];
      l[1] = lat(ix + 1, iy);
      l[3] = lat(ix + 1, iy + 1);
      cache.ix[oct] = ix;
    } else if (!cache.valid[oct] || cache.ix[oct] != ix || cache.iy[oct] != iy) {
      l[0] = lat(ix, iy);
      l[1] = lat(ix + 1, iy);
      l[2] = lat(ix, iy + 1);
      l[3] = lat(ix + 1, iy + 1);
      cache.ix[oct] = ix;
      cache.iy[oct] = iy;
      cache.valid[oct] = true;
    }
    const double v = (l[0] * (1 - tx) + l[1] * tx) * (1 - ty) + (l[2] * (1 - tx) + l[3] * tx) * ty;
    sum += amp * v;
    norm += amp;
    amp *= 0.5;
    freq *= 2.0;
  }
  return sum / norm;
}

// ---- the scene -------------------------------------------------------------------------------

struct Scene {
  const IceFraction& ice;
  const IcePhotoOptions& opt;
  GridGeometry geo;
  Occupancy occ;                        // empty-space skipping (disabled: every block is marked)
  std::vector<std::uint8_t> cell_live;  // dilated_nonzero (with occ)
  std::vector<double> zenith_sum;       // per column: Σ over the zenith march's z samples (see zenith_T)
  double zenith_dt = 0;
  bool zenith_hit = false;
  Vec3d to_lamp;
  double step = 0;
  Box box;                        // where f > 0 can be sampled
  Grid3<float> lamp_T;            // Shadow::kGrid: transmittance towards the lamp at cell centres
  std::array<double, 3> a_rgb{};  // albedo × tint

  Scene(const IceFraction& g, const IcePhotoOptions& o) : ice(g), opt(o), geo(g) {
    if (g.empty() || !(g.h_m > 0)) throw InputError("render_ice_photo: empty ice grid or non-positive cell size");
    if (!(o.to_lamp.z() > 0.0) || !o.to_lamp.allFinite())
      throw InputError("render_ice_photo: to_lamp must point upwards (z > 0)");
    if (!(o.extinction_per_m >= 0.0) || !(o.hg_g > -1.0 && o.hg_g < 1.0) || o.supersample < 1 || !(o.step_m >= 0.0))
      throw InputError("render_ice_photo: bad options (extinction >= 0, -1 < hg_g < 1, supersample >= 1, step >= 0)");
    to_lamp = o.to_lamp.normalized();
    step = o.step_m > 0 ? o.step_m : 0.5 * g.h_m;
    box = support_box(g, 0.0, true);
    if (o.skip_empty_space && !box.empty && o.extinction_per_m > 0) {
      occ = Occupancy(g);
      cell_live = dilated_nonzero(g);
      build_zenith_table();
    }
    for (int c = 0; c < 3; ++c) a_rgb[std::size_t(c)] = o.albedo * o.ice_tint_rgb[std::size_t(c)];
    if (o.shadow == IcePhotoOptions::Shadow::kGrid && !box.empty && o.extinction_per_m > 0) build_lamp_grid();
  }

  /// 0: the point's block is unmarked; 1: its block is marked but f = 0 at the point (no non-zero
  /// cell in the 3³ neighbourhood of its cell, which holds its stencil); 2: f may be non-zero.
  int liveness(double gx, double gy, double gz, int& bx, int& by, int& bz) const {
    constexpr int B = Occupancy::kBlock;
    const int cx = std::clamp(static_cast<int>(std::floor(gx + 0.5)), 0, geo.nx - 1);
    const int cy = std::clamp(static_cast<int>(std::floor(gy + 0.5)), 0, geo.ny - 1);
    const int cz = std::clamp(static_cast<int>(std::floor(gz + 0.5)), 0, geo.nz - 1);
    bx = cx / B;
    by = cy / B;
    bz = cz / B;
    if (!occ.marked[std::size_t(bx) + std::size_t(occ.bx) * (std::size_t(by) + std::size_t(occ.by) * std::size_t(bz))])
      return 0;
    return cell_live[ice.index(cx, cy, cz)] ? 2 : 1;
  }

  /// Per column (i, j): Σ_i (1 - tz_i) v(i, j, k0_i) + tz_i v(i, j, k1_i) over the z samples of the
  /// zenith shadow march from the ground plane; the march's Σ f is the bilinear interpolant of
  /// these sums (the trilinear weights factor), so zenith_T needs no march (equal up to rounding).
  void build_zenith_table() {
    const Vec3d o(0.5 * (box.lo.x() + box.hi.x()), 0.5 * (box.lo.y() + box.hi.y()), opt.ground_z_m);
    const Vec3d d(0, 0, 1);
    double t0 = 0, t1 = 0;
    zenith_hit = false;
    if (!slab(box, o, d, t0, t1)) return;
    t0 = std::max(t0, 0.0);
    if (!(t1 > t0)) return;
    const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
    zenith_dt = (t1 - t0) / n;
    zenith_sum.assign(std::size_t(ice.nx) * std::size_t(ice.ny), 0.0);
    const std::size_t sz = std::size_t(ice.nx) * std::size_t(ice.ny);
    for (int i = 0; i < n; ++i) {
      const double z = o.z() + (t0 + (i + 0.5) * zenith_dt);
      const double gz = (z - ice.origin_m.z()) / ice.h_m - 0.5;
      if (gz < -0.5 || gz > ice.nz - 0.5) continue;
      const double fz = std::floor(gz), tz = gz - fz;
      const std::size_t k0 = sz * std::size_t(std::clamp(int(fz), 0, ice.nz - 1));
      const std::size_t k1 = sz * std::size_t(std::clamp(int(fz) + 1, 0, ice.nz - 1));
      for (std::size_t c = 0; c < sz; ++c)
        zenith_sum[c] += double(ice.value[k0 + c]) * (1 - tz) + double(ice.value[k1 + c]) * tz;
    }
    zenith_hit = true;
  }

  /// march_T(g, +z) for a point g on the ground plane, from the column table.
  double zenith_T(const Vec3d& g) const {
    if (!zenith_hit) return 1.0;
    if (g.x() < box.lo.x() || g.x() > box.hi.x() || g.y() < box.lo.y() || g.y() > box.hi.y()) return 1.0;
    const double gx = (g.x() - geo.origin.x()) / geo.h - 0.5, gy = (g.y() - geo.origin.y()) / geo.h - 0.5;
    if (gx < -0.5 || gy < -0.5 || gx > geo.nx - 0.5 || gy > geo.ny - 0.5) return 1.0;
    const double fx = std::floor(gx), fy = std::floor(gy), tx = gx - fx, ty = gy - fy;
    const std::size_t sy = std::size_t(geo.nx);
    const std::size_t x0 = std::size_t(std::clamp(int(fx), 0, geo.nx - 1)),
                      x1 = std::size_t(std::clamp(int(fx) + 1, 0, geo.nx - 1));
    const std::size_t y0 = sy * std::size_t(std::clamp(int(fy), 0, geo.ny - 1)),
                      y1 = sy * std::size_t(std::clamp(int(fy) + 1, 0, geo.ny - 1));
    const double* S = zenith_sum.data();
    const double sum =
        (S[x0 + y0] * (1 - tx) + S[x1 + y0] * tx) * (1 - ty) + (S[x0 + y1] * (1 - tx) + S[x1 + y1] * tx) * ty;
    return std::exp(-opt.extinction_per_m * sum * zenith_dt);
  }

  /// ice.sample(p), bit for bit, but 0 at once in unmarked blocks.
  double sample_ice(const Vec3d& p) const {
    double gx, gy, gz;
    if (!geo.coords(p, gx, gy, gz)) return 0.0;
    int bx, by, bz;
    if (occ.enabled() && liveness(gx, gy, gz, bx, by, bz) < 2) return 0.0;
    Stencil st;
    geo.stencil(gx, gy, gz, st);
    return GridGeometry::interpolate(ice.value.data(), st);
  }

  /// The midpoint samples x_i = o + (t0 + (i + ½) dt) d, i < n, of a ray: calls fn(x_i, f_i, stencil)
  /// for each sample inside the grid, in order, until it returns false, except samples where f = 0
  /// is known beforehand (unmarked blocks, skipped a block at a time; dead cells): the positions and values of the
  /// others are those of the plain loop, so the result is the same.
  template <class Fn>
  void march(const Vec3d& o, const Vec3d& d, double t0, int n, double dt, const Fn& fn) const {
    const float* v = ice.value.data();
    const bool skip = occ.enabled();
    constexpr int B = Occupancy::kBlock;
    // Skip distances need no exact rounding (an unmarked block is empty a cell beyond its faces).
    const double inv_d[3] = {1.0 / d.x(), 1.0 / d.y(), 1.0 / d.z()}, inv_dt = 1.0 / dt;
    for (int i = 0; i < n;) {
      const Vec3d x = o + (t0 + (i + 0.5) * dt) * d;
      double gx, gy, gz;
      if (!geo.coords(x, gx, gy, gz)) {
        ++i;
        continue;
      }
      int b[3];
      const int live = skip ? liveness(gx, gy, gz, b[0], b[1], b[2]) : 2;
      if (live == 1) {  // f = 0 here: nothing to add
        ++i;
        continue;
      }
      if (live == 0) {
        // Leave the block: the first sample at or beyond its exit.
        const int nb[3] = {occ.bx, occ.by, occ.bz};
        double t_exit = kInf;
        for (int a = 0; a < 3; ++a) {
          if (d[a] > 0.0) {
            if (b[a] + 1 < nb[a])
              t_exit = std::min(t_exit, (geo.origin[a] + geo.h * ((b[a] + 1) * B) - o[a]) * inv_d[a]);
          } else if (d[a] < 0.0) {
            if (b[a] > 0) t_exit = std::min(t_exit, (geo.origin[a] + geo.h * (b[a] * B) - o[a]) * inv_d[a]);
          }
        }
        const double q = std::ceil((t_exit - t0) * inv_dt - 0.5);
        i = q >= double(n) ? n : std::max(i + 1, static_cast<int>(q));
        continue;
      }
      Stencil st;
      geo.stencil(gx, gy, gz, st);
      if (!fn(x, GridGeometry::interpolate(v, st), st)) return;
      ++i;
    }
  }

  /// Transmittance from x along unit direction dir to the exit of the ice box (midpoint rule
  /// with equal steps ≤ step: exact for homogeneous media).
  double march_T(const Vec3d& x, const Vec3d& dir) const {
    double t0 = 0, t1 = 0;
    if (!slab(box, x, dir, t0, t1)) return 1.0;
    t0 = std::max(t0, 0.0);
    if (!(t1 > t0)) return 1.0;
    const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
    const double dt = (t1 - t0) / n;
    double sum = 0;
    march(x, dir, t0, n, dt, [&](const Vec3d&, double f, const Stencil&) {
      sum += f;
      return true;
    });
    return std::exp(-opt.extinction_per_m * sum * dt);
  }

  void build_lamp_grid() {
    lamp_T = Grid3<float>(ice.nx, ice.ny, ice.nz, ice.h_m, ice.origin_m, 1.0f);
    const double h = ice.h_m;
    // Cells entirely above the ice box see the lamp unobstructed (T = 1): the lamp is above.
    const int k_top = std::min(ice.nz - 1, int(std::ceil((box.hi.z() - ice.origin_m.z()) / h - 0.5)));
    const double len = h / to_lamp.z();  // from one layer's centre plane to the next one's
    const Vec3d off = to_lamp * len;
    const Vec3d lo = ice.min_m(), hi = ice.max_m();
    for (int k = k_top; k >= 0; --k) {
      auto layer = [&](int j0, int j1) {
        double last_f = -1.0, last_att = 1.0;
        for (int j = j0; j < j1; ++j)
          for (int i = 0; i < ice.nx; ++i) {
            const Vec3d c = ice.centre_m(i, j, k);
            const Vec3d q = c + off;
            double T;
            if (k == k_top || q.x() < lo.x() || q.x() > hi.x() || q.y() < lo.y() || q.y() > hi.y()) {
              T = march_T(c, to_lamp);
            } else {
              // Bilinear in layer k + 1 (clamped to its centres) times Simpson's rule on the step.
              const double gx = std::clamp((q.x() - ice.origin_m.x()) / h - 0.5, 0.0, ice.nx - 1.0);
              const double gy = std::clamp((q.y() - ice.origin_m.y()) / h - 0.5, 0.0, ice.ny - 1.0);
              const int i0 = std::min(int(gx), ice.nx - 1), j0b = std::min(int(gy), ice.ny - 1);
              const int i1 = std::min(i0 + 1, ice.nx - 1), j1b = std::min(j0b + 1, ice.ny - 1);
              const double tx = gx - i0, ty = gy - j0b;
              auto Tu = [&](int a, int b) { return double(lamp_T.at(a, b, k + 1)); };
              const double up = (Tu(i0, j0b) * (1 - tx) + Tu(i1, j0b) * tx) * (1 - ty) +
                                (Tu(i0, j1b) * (1 - tx) + Tu(i1, j1b) * tx) * ty;
              const double f = (sample_ice(c) + 4.0 * sample_ice(c + 0.5 * off) + sample_ice(q)) / 6.0;
              if (f != last_f) {  // air and solid ice repeat f
                last_f = f;
                last_att = std::exp(-opt.extinction_per_m * f * len);
              }
              T = up * last_att;
            }
            lamp_T.at(i, j, k) = float(T);
          }
      };
      if (opt.parallel) {
        tbb::parallel_for(tbb::blocked_range<int>(0, ice.ny, 8),
                          [&](const tbb::blocked_range<int>& r) { layer(r.begin(), r.end()); });
      } else {
        layer(0, ice.ny);
      }
    }
  }

  /// Linear RGB radiance along the ray o + t d (d unit).
  std::array<double, 3> trace(const Vec3d& o, const Vec3d& d, TextureCache& texture) const {
    std::array<double, 3> rad{0, 0, 0};
    double T = 1.0;
    double t_ground = kInf;
    if (d.z() < 0.0) t_ground = (opt.ground_z_m - o.z()) / d.z();
    if (t_ground < 0.0) t_ground = kInf;  // camera below the ground: no ground in view
    double t0 = 0, t1 = 0;
    if (opt.extinction_per_m > 0 && slab(box, o, d, t0, t1)) {
      t0 = std::max(t0, 0.0);
      t1 = std::min(t1, t_ground);
      if (t1 > t0) {
        const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
        const double dt = (t1 - t0) / n;
        const double p = henyey_greenstein(to_lamp.dot(d), opt.hg_g);
        const bool scatter = opt.albedo > 0.0;
        const float* lamp =
            opt.shadow == IcePhotoOptions::Shadow::kGrid && !lamp_T.empty() ? lamp_T.value.data() : nullptr;
        bool opaque = false;
        double last_f = -1.0, last_att = 1.0;  // solid ice repeats f (and so the attenuation)
        march(o, d, t0, n, dt, [&](const Vec3d& x, double f, const Stencil& st) {
          if (f <= 0.0) return true;
          if (f != last_f) {
            last_f = f;
            last_att = std::exp(-opt.extinction_per_m * f * dt);
          }
          const double att = last_att;
          if (scatter) {
            // ∫ over the step of a σ (L p T_lamp + sky) e^{-σ s} ds = a (L p T_lamp + sky)(1 - att)
            double Tl = 1.0;  // T_lamp(x): Shadow::kNone, or kGrid without a grid
            if (lamp) {
              Tl = GridGeometry::interpolate(lamp, st);  // = lamp_T.sample(x, 1.0): x is inside the grid
            } else if (opt.shadow == IcePhotoOptions::Shadow::kMarch) {
              Tl = march_T(x, to_lamp);
            }
            const double s = (opt.lamp_irradiance * p * Tl + opt.sky_radiance) * (1.0 - att) * T;
            for (std::size_t c = 0; c < 3; ++c) rad[c] += a_rgb[c] * s;
          }
          T *= att;
          if (T < opt.min_transmittance) {
            opaque = true;
            return false;
          }
          return true;
        });
        if (opaque) return rad;
      }
    }
    if (t_ground == kInf) {  // the sky
      for (auto& r : rad) r += T * opt.sky_radiance;
      return rad;
    }
    const Vec3d g = o + t_ground * d;
    const double rho =
        opt.ground_albedo *
        std::max(0.0, 1.0 + opt.ground_texture_contrast * ground_texture_impl(g.x(), g.y(), opt.ground_texture_scale_m,
                                                                              opt.ground_seed, texture));
    double Tl = 1.0, Tz = 1.0;
    if (opt.shadow != IcePhotoOptions::Shadow::kNone && opt.extinction_per_m > 0) {
      Tl = march_T(g, to_lamp);
      Tz = occ.enabled() ? zenith_T(g) : march_T(g, Vec3d(0, 0, 1));
    }
    const double e = rho * (opt.lamp_irradiance / std::numbers::pi * to_lamp.z() * Tl + opt.sky_radiance * Tz);
    for (std::size_t c = 0; c < 3; ++c) rad[c] += T * e * opt.ground_tint_rgb[c];
    return rad;
  }
};

template <class RowFn>
void for_rows(int rows, bool parallel, const RowFn& fn) {
  if (parallel) {
    tbb::parallel_for(tbb::blocked_range<int>(0, rows, 4), [&](const tbb::blocked_range<int>& r) {
      for (int v = r.begin(); v < r.end(); ++v) fn(v);
    });
  } else {
    for (int v = 0; v < rows; ++v) fn(v);
  }
}

double top_of_scene(const IceFraction& ice, double ground_z) { return std::max(ice.max_m().z(), ground_z) + 1.0; }

}  // namespace

double ground_texture(double x_m, double y_m, double scale_m, std::uint64_t seed) {
  TextureCache cache;
  return ground_texture_impl(x_m, y_m, scale_m, seed, cache);
}

cv::Mat render_ice_radiance(const IceFraction& ice_in, const Camera& camera, const IcePhotoOptions& options,
                            const cv::Mat& only) {
  if (!(options.interface_width >= 0.0) || !std::isfinite(options.interface_width))
    throw InputError(
        fmt::format("ice photo: interface_width must be a finite number >= 0 (got {})", options.interface_width));
  IceFraction sharpened;
  if (options.interface_width > 0) {
    sharpened = ice_in;
    const float w = static_cast<float>(options.interface_width);
    for (float& f : sharpened.value) f = std::clamp((f - 0.5F) / w + 0.5F, 0.0F, 1.0F);
  }
  const IceFraction& ice = options.interface_width > 0 ? sharpened : ice_in;
  const Scene scene(ice, options);
  const int W = camera_width(camera), H = camera_height(camera);
  const RayGenerator gen(camera, top_of_scene(ice, options.ground_z_m));
  const int k = options.supersample;
  if (!only.empty() && (only.type() != CV_8UC1 || only.cols != W || only.rows != H))
    throw InputError("render_ice_radiance: the pixel selection must be CV_8UC1 of the image size");
  cv::Mat out(H, W, CV_32FC3, cv::Scalar::all(0));
  for_rows(H, options.parallel, [&](int v) {
    auto* row = out.ptr<cv::Vec3f>(v);
    const std::uint8_t* sel = only.empty() ? nullptr : only.ptr<std::uint8_t>(v);
    TextureCache texture;
    for (int u = 0; u < W; ++u) {
      if (sel && !sel[u]) continue;
      std::array<double, 3> acc{0, 0, 0};
      for (int t = 0; t < k; ++t)
        for (int s = 0; s < k; ++s) {
          const CameraRay ray = gen.generate_ray(u - 0.5 + (s + 0.5) / k, v - 0.5 + (t + 0.5) / k);
          if (!ray.ok) continue;
          const auto r = scene.trace(ray.origin, ray.direction, texture);
          for (std::size_t c = 0; c < 3; ++c) acc[c] += r[c];
        }
      const double inv = 1.0 / (k * k);
      row[u] = cv::Vec3f(float(acc[2] * inv), float(acc[1] * inv), float(acc[0] * inv));  // BGR
    }
  });
  return out;
}

cv::Mat develop_photo(const cv::Mat& radiance, const IcePhotoOptions& options) {
  if (radiance.type() != CV_32FC3) throw InputError("develop_photo: radiance must be CV_32FC3");
  cv::Mat lin = radiance * options.exposure;
  if (options.lens_blur_sigma_px > 0) {
    cv::GaussianBlur(lin, lin, cv::Size(0, 0), options.lens_blur_sigma_px, options.lens_blur_sigma_px,
                     cv::BORDER_REFLECT);
  }
  cv::Mat out(lin.size(), CV_8UC3);
  const double inv_gamma = options.gamma > 0 ? 1.0 / options.gamma : 1.0;
  for_rows(lin.rows, options.parallel, [&](int v) {
    const auto* in = lin.ptr<cv::Vec3f>(v);
    auto* o = out.ptr<cv::Vec3b>(v);
    for (int u = 0; u < lin.cols; ++u)
      for (int c = 0; c < 3; ++c) {
        double x = 255.0 * std::pow(std::clamp(double(in[u][c]), 0.0, 1.0), inv_gamma);
        if (options.noise_sigma > 0) {
          const std::uint64_t id =
              (std::uint64_t(v) * std::uint64_t(lin.cols) + std::uint64_t(u)) * 3 + std::uint64_t(c);
          const std::uint64_t h = hash3(options.seed, id, 0x6e6f697365ull);
          const double u1 = to_unit(h), u2 = to_unit(splitmix64(h));
          x += options.noise_sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
        }
        o[u][c] = static_cast<std::uint8_t>(std::clamp(std::lround(x), 0L, 255L));
      }
  });
  return out;
}

cv::Mat render_ice_photo(const IceFraction& ice, const Camera& camera, const IcePhotoOptions& options) {
  return develop_photo(render_ice_radiance(ice, camera, options), options);
}

cv::Mat ice_true_mask(const IceFraction& ice, const Camera& camera, double threshold, double ground_z_m) {
  if (ice.empty() || !(ice.h_m > 0)) throw InputError("ice_true_mask: empty ice grid or non-positive cell size");
  const int W = camera_width(camera), H = camera_height(camera);
  cv::Mat mask(H, W, CV_8UC1, cv::Scalar(0));
  const Box box = support_box(ice, threshold, threshold <= 0.0);
  if (box.empty) return mask;
  const RayGenerator gen(camera, top_of_scene(ice, ground_z_m));
  const double step = ice.h_m / 8.0;
  for_rows(H, true, [&](int v) {
    auto* row = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < W; ++u) {
      const CameraRay ray = gen.generate_ray(u, v);
      if (!ray.ok) continue;
      const Vec3d& o = ray.origin;
      const Vec3d& d = ray.direction;
      double t0 = 0, t1 = 0;
      if (!slab(box, o, d, t0, t1)) continue;
      t0 = std::max(t0, 0.0);
      if (d.z() < 0.0) {
        const double tg = (ground_z_m - o.z()) / d.z();
        if (tg >= 0.0) t1 = std::min(t1, tg);
      }
      if (!(t1 >= t0)) continue;
      const int n = std::max(1, int(std::ceil((t1 - t0) / step)));
      const double dt = (t1 - t0) / n;
      for (int i = 0; i <= n; ++i)
        if (ice.sample(o + (t0 + i * dt) * d) >= threshold) {
          row[u] = 255;
          break;
        }
    }
  });
  return mask;
}

void write_jpeg(const std::filesystem::path& file, const cv::Mat& image, int quality) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    throw InputError(fmt::format("{}: write_jpeg needs a non-empty 8-bit gray or BGR image", file.string()));
  if (quality < 1 || quality > 100)
    throw InputError(fmt::format("{}: JPEG quality must be in [1, 100] (got {})", file.string(), quality));
  // OpenCV's BGR to the image type's RGB.
  Image8 pixels(image.cols, image.rows, image.channels());
  for (int y = 0; y < image.rows; ++y) {
    const std::uint8_t* in = image.ptr<std::uint8_t>(y);
    for (int x = 0; x < image.cols; ++x)
      for (int c = 0; c < image.channels(); ++c)
        pixels.at(x, y, c) = in[x * image.channels() + (image.channels() == 3 ? 2 - c : c)];
  }
  write_image(file, pixels, quality);
}

}  // namespace meltlab::render
