// Seed 001's transfer-function model in the volume integrator (see integrator/volume_integrator.h
// and ../shared/spec/cpu-large-volumes.md): the storage both layouts share, the empty-space
// indexes, the per-segment compositing, and the two traversals (image order; the object-order
// tiles x blocks renderer with global ERT).
//
// One lookup rule for every storage (so the layouts agree bit for bit): a sample at index
// coordinates g is clamped to [0, N - 1] per axis; its cell's lower corner is i = min(⌊g⌋, N - 2)
// and its weight g - i; the 8 voxels are read through per-axis offset tables (dense: i · stride;
// blocks: the block's offset plus the local one, both separable per axis) and blended along x,
// then y, then z as a + (b - a) t. With N ≥ 2 the cell never leaves the volume, and in the blocked
// layout never leaves its block (local corner ≤ B - 2).

#include <meltlab/core/time.h>
#include <meltlab/core/error.h>

#include "volume_tracer_state.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/combinable.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/flow_graph.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <thread>
#include <vector>

namespace meltlab::render {

namespace {

using Vec3 = Eigen::Vector3d;
using detail::SampleGrid;
using detail::TracerState;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr int kCellShift = 2;    // clv.ess.cell: 4 voxels
constexpr int kRegionShift = 5;  // the multi-level index's upper level: 32 voxels (8³ cells)

// ---- storage ----------------------------------------------------------------------------------

/// A located sample: its cell's lower corner and the weights.
struct Loc {
  int i[3];
  float t[3];
};

/// The lookup rule (see the file comment).
inline Loc locate(const double g[3], const int n[3]) {
  Loc L;
  for (int a = 0; a < 3; ++a) {
    const double x = std::clamp(g[a], 0.0, double(n[a] - 1));
    const int i = std::min(int(x), n[a] - 2);  // x >= 0: int() is the floor
    L.i[a] = i;
    L.t[a] = float(x - double(i));
  }
  return L;
}

inline float lerp(float a, float b, float t) { return a + (b - a) * t; }

/// Either layout behind per-axis offset tables: voxel (i, j, k) is data[off[0][i] + off[1][j] +
/// off[2][k]], and a cell's neighbours along each axis are `step` further (inside one block).
template <class T>
struct Store {
  const T* data = nullptr;
  int n[3] = {0, 0, 0};
  std::vector<std::int64_t> off[3];
  std::int64_t step[3] = {0, 0, 0};
  float scale = 1;
  bool unit_scale = true;

  /// The value at a located sample.
  [[gnu::always_inline]] float fetch(const Loc& L) const {
    const T* p = data + off[0][std::size_t(L.i[0])] + off[1][std::size_t(L.i[1])] + off[2][std::size_t(L.i[2])];
    const std::int64_t ox = step[0], oy = step[1], oz = step[2];
    auto v = [p](std::int64_t o) { return static_cast<float>(p[o]); };
    const float c00 = lerp(v(0), v(ox), L.t[0]);
    const float c10 = lerp(v(oy), v(ox + oy), L.t[0]);
    const float c01 = lerp(v(oz), v(ox + oz), L.t[0]);
    const float c11 = lerp(v(oy + oz), v(ox + oy + oz), L.t[0]);
    const float f = lerp(lerp(c00, c10, L.t[1]), lerp(c01, c11, L.t[1]), L.t[2]);
    return unit_scale ? f : f * scale;
  }
  T stored(int i, int j, int k) const {
    return data[off[0][std::size_t(i)] + off[1][std::size_t(j)] + off[2][std::size_t(k)]];
  }
  float value_of(T stored_number) const { return unit_scale ? float(stored_number) : float(stored_number) * scale; }
};

template <class T>
Store<T> dense_store(const Volume& v) {
  Store<T> s;
  const VolumeSamples<T> vs = v.samples<T>();
  s.data = vs.data;
  const std::int64_t stride[3] = {vs.sx, vs.sy, vs.sz};
  for (int a = 0; a < 3; ++a) {
    s.n[a] = v.dims()[std::size_t(a)];
    s.off[a].resize(std::size_t(s.n[a]));
    for (int i = 0; i < s.n[a]; ++i) s.off[a][std::size_t(i)] = i * stride[a];
    s.step[a] = stride[a];
  }
  s.scale = vs.scale;
  s.unit_scale = vs.scale == 1.0f;
  return s;
}

template <class T>
Store<T> brick_store(const BrickedVolume& v) {
  Store<T> s;
  const BrickSamples<T> b = v.samples<T>();
  s.data = b.data;
  const std::int64_t B = b.side;
  // Block (bx, by, bz) starts at ((bx nb_y + by) nb_z + bz) B³; local (lx, ly, lz) at (lx B + ly) B + lz:
  // both separable per axis.
  const std::int64_t block_unit[3] = {std::int64_t(b.nb[1]) * b.nb[2] * B * B * B, std::int64_t(b.nb[2]) * B * B * B,
                                      B * B * B};
  const std::int64_t local_unit[3] = {B * B, B, 1};
  for (int a = 0; a < 3; ++a) {
    s.n[a] = b.n[a];
    s.off[a].resize(std::size_t(s.n[a]));
    for (int i = 0; i < s.n[a]; ++i) {
      // Cells (i <= N - 2) use the block that owns them; voxel N - 1 is the last cell's far corner.
      const int c = std::min(i, s.n[a] - 2);
      const int blk = c / b.stride;
      s.off[a][std::size_t(i)] = blk * block_unit[a] + (i - blk * b.stride) * local_unit[a];
    }
    s.step[a] = local_unit[a];
  }
  s.scale = b.scale;
  s.unit_scale = b.scale == 1.0f;
  return s;
}

// ---- the range index and the empty-space flags -------------------------------------------------

int cells_per_axis(int n, int shift) { return ((n - 2) >> shift) + 1; }

/// Per 4³ cell the min and max of its S + 1 stored voxels per axis; per block of a bricked volume
/// the min and max of its B³ stored samples (padding included).
template <class T>
class RangeIndex final : public VolumeRangeIndex {
 public:
  int n0[3] = {0, 0, 0};
  std::vector<T> cell_min, cell_max;
  std::vector<T> block_min, block_max;  // bricked volumes
  std::size_t cell(int cx, int cy, int cz) const {
    return std::size_t(cx) + std::size_t(n0[0]) * (std::size_t(cy) + std::size_t(n0[1]) * std::size_t(cz));
  }
  void set_meta(const std::array<int, 3>& d, double ms) {
    dims_ = d;
    build_ms_ = ms;
    memory_bytes_ = std::int64_t((cell_min.size() * 2 + block_min.size() * 2) * sizeof(T));
  }
};

/// For every 4³ cell, merge(map(voxel)) over its S + 1 voxels per axis; parallel over x columns of
/// cells, each voxel read once per column (twice on the planes that columns share).
template <class T, class V, class Map, class Merge>
std::vector<V> reduce_cells(const Store<T>& st, const int n0[3], V init, const Map& map, const Merge& merge) {
  std::vector<V> out(
      static_cast<std::size_t>(n0[0]) * static_cast<std::size_t>(n0[1]) * static_cast<std::size_t>(n0[2]), init);
  const int nx = st.n[0], ny = st.n[1], nz = st.n[2];
  tbb::parallel_for(tbb::blocked_range<int>(0, n0[0]), [&](const tbb::blocked_range<int>& r) {
    std::vector<V> row(static_cast<std::size_t>(n0[2]));
    for (int cx = r.begin(); cx < r.end(); ++cx) {
      const int x0 = cx << kCellShift, x1 = std::min(x0 + (1 << kCellShift), nx - 1);
      for (int x = x0; x <= x1; ++x)
        for (int y = 0; y < ny; ++y) {
          // The row's per-cell reduction along z: voxels [4 cz, 4 cz + 4].
          for (int cz = 0; cz < n0[2]; ++cz) {
            const int z0 = cz << kCellShift, z1 = std::min(z0 + (1 << kCellShift), nz - 1);
            V v = init;
            for (int z = z0; z <= z1; ++z) v = merge(v, map(st.stored(x, y, z)));
            row[std::size_t(cz)] = v;
          }
          // Voxel row y belongs to cell y/4, and (on a cell plane) to the cell before.
          const int cy_a = y >> kCellShift;
          const int cy_b = ((y & ((1 << kCellShift) - 1)) == 0 && y > 0) ? cy_a - 1 : -1;
          for (int cy : {cy_a, cy_b}) {
            if (cy < 0 || cy >= n0[1]) continue;
            V* dst = &out[std::size_t(cx) + std::size_t(n0[0]) * std::size_t(cy)];
            const std::size_t zstride = std::size_t(n0[0]) * std::size_t(n0[1]);
            for (int cz = 0; cz < n0[2]; ++cz)
              dst[std::size_t(cz) * zstride] = merge(dst[std::size_t(cz) * zstride], row[std::size_t(cz)]);
          }
        }
    }
  });
  return out;
}

template <class T>
std::shared_ptr<RangeIndex<T>> build_cell_ranges(const Store<T>& st) {
  const auto t0 = std::chrono::steady_clock::now();
  auto ix = std::make_shared<RangeIndex<T>>();
  for (int a = 0; a < 3; ++a) ix->n0[a] = cells_per_axis(st.n[a], kCellShift);
  struct MinMax {
    T lo, hi;
  };
  const MinMax init{std::numeric_limits<T>::max(), std::numeric_limits<T>::lowest()};
  const auto mm = reduce_cells(
      st, ix->n0, init,
      [](T v) {
        return MinMax{v, v};
      },
      [](const MinMax& a, const MinMax& b) {
        return MinMax{std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
      });
  ix->cell_min.resize(mm.size());
  ix->cell_max.resize(mm.size());
  for (std::size_t i = 0; i < mm.size(); ++i) ix->cell_min[i] = mm[i].lo, ix->cell_max[i] = mm[i].hi;
  ix->set_meta({st.n[0], st.n[1], st.n[2]}, ms_since(t0));
  return ix;
}

template <class T>
void add_block_ranges(RangeIndex<T>& ix, const BrickedVolume& v) {
  const auto t0 = std::chrono::steady_clock::now();
  const BrickSamples<T> b = v.samples<T>();
  const std::int64_t nblocks = v.block_count();
  ix.block_min.resize(std::size_t(nblocks));
  ix.block_max.resize(std::size_t(nblocks));
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, nblocks), [&](const auto& r) {
    for (std::int64_t k = r.begin(); k < r.end(); ++k) {
      const T* p = b.data + k * b.block_elems;
      T lo = p[0], hi = p[0];
      for (std::int64_t i = 1; i < b.block_elems; ++i) lo = std::min(lo, p[i]), hi = std::max(hi, p[i]);
      ix.block_min[std::size_t(k)] = lo;
      ix.block_max[std::size_t(k)] = hi;
    }
  });
  ix.set_meta(ix.dims(), ix.build_ms() + ms_since(t0));
}

/// The TF-dependent flags.
struct EmptySpace {
  int n0[3] = {0, 0, 0}, n1[3] = {0, 0, 0};
  std::vector<std::uint8_t> live0, live1;  // 4³ cells, 32³ regions
  std::vector<std::uint8_t> block_live;    // bricked volumes: per-block visibility

  bool cell_live(const Loc& L) const {
    return live0[std::size_t(L.i[0] >> kCellShift) +
                 std::size_t(n0[0]) *
                     (std::size_t(L.i[1] >> kCellShift) + std::size_t(n0[1]) * std::size_t(L.i[2] >> kCellShift))] != 0;
  }
  bool region_live(const Loc& L) const {
    return live1[std::size_t(L.i[0] >> kRegionShift) +
                 std::size_t(n1[0]) * (std::size_t(L.i[1] >> kRegionShift) +
                                       std::size_t(n1[1]) * std::size_t(L.i[2] >> kRegionShift))] != 0;
  }
};

/// Whether [lo, hi] (values) may hold a visible interpolated value. Float samples: widened by a
/// relative 1e-5, more than the rounding of the three lerps (a few ulp) can move a blend outside
/// its voxels' range; 8/16-bit samples are whole numbers, (b - a) is exact and the blend stays in.
template <class T>
bool range_visible(const TransferFunction& tf, double lo, double hi) {
  if constexpr (std::is_floating_point_v<T>) {
    const double pad = 1e-5 * (std::abs(lo) + std::abs(hi)) + 1e-30;
    lo -= pad;
    hi += pad;
  }
  return tf.visible_in(lo, hi);
}

template <class T>
EmptySpace build_empty_space(const Store<T>& st, const RangeIndex<T>& ix, const TransferFunction& tf,
                             EmptyCellTest test, const BrickedVolume* bricked) {
  EmptySpace e;
  for (int a = 0; a < 3; ++a) {
    e.n0[a] = ix.n0[a];
    e.n1[a] = cells_per_axis(st.n[a], kRegionShift);
  }
  if (test == EmptyCellTest::kRange) {
    e.live0.resize(ix.cell_min.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, e.live0.size(), 1 << 14), [&](const auto& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i)
        e.live0[i] = range_visible<T>(tf, st.value_of(ix.cell_min[i]), st.value_of(ix.cell_max[i])) ? 1 : 0;
    });
  } else {
    // The source's test: some voxel of the S + 1 maps to α > 0.
    std::vector<std::uint8_t> lut;
    if constexpr (sizeof(T) == 1) {
      lut.resize(256);
      for (int v = 0; v < 256; ++v) lut[std::size_t(v)] = tf.visible_at(st.value_of(T(v))) ? 1 : 0;
    }
    auto visible = [&](T v) -> std::uint8_t {
      if constexpr (sizeof(T) == 1) return lut[std::size_t(v)];
      return tf.visible_at(st.value_of(v)) ? 1 : 0;
    };
    e.live0 = reduce_cells(st, ix.n0, std::uint8_t(0), visible,
                           [](std::uint8_t a, std::uint8_t b) { return std::uint8_t(a | b); });
  }
  // Regions: any live cell.
  e.live1.assign(std::size_t(e.n1[0]) * std::size_t(e.n1[1]) * std::size_t(e.n1[2]), 0);
  constexpr int f = 1 << (kRegionShift - kCellShift);
  for (int cz = 0; cz < e.n0[2]; ++cz)
    for (int cy = 0; cy < e.n0[1]; ++cy)
      for (int cx = 0; cx < e.n0[0]; ++cx)
        if (e.live0[ix.cell(cx, cy, cz)])
          e.live1[std::size_t(cx / f) +
                  std::size_t(e.n1[0]) * (std::size_t(cy / f) + std::size_t(e.n1[1]) * std::size_t(cz / f))] = 1;
  if (bricked) {
    e.block_live.resize(std::size_t(bricked->block_count()));
    const BrickSamples<T> b = bricked->samples<T>();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, e.block_live.size()), [&](const auto& r) {
      for (std::size_t k = r.begin(); k < r.end(); ++k) {
        if (test == EmptyCellTest::kRange) {
          e.block_live[k] = range_visible<T>(tf, st.value_of(ix.block_min[k]), st.value_of(ix.block_max[k])) ? 1 : 0;
        } else {
          const T* p = b.data + std::int64_t(k) * b.block_elems;
          bool any = false;
          for (std::int64_t i = 0; i < b.block_elems && !any; ++i) any = tf.visible_at(st.value_of(p[i]));
          e.block_live[k] = any ? 1 : 0;
        }
      }
    });
  }
  return e;
}

// ---- one ray ----------------------------------------------------------------------------------

/// A ray in index space and its sample grid: sample k at g = g0 + (a + k h) gv, k < n.
struct RayGrid {
  double g0[3], gv[3], inv_gv[3];
  double a, h;
  std::int64_t n;
  float view[3];  // unit world direction towards the eye (v₋), for the specular term

  [[gnu::always_inline]] void at(std::int64_t k, double g[3]) const {
    const double t = a + double(k) * h;
    g[0] = g0[0] + t * gv[0];
    g[1] = g0[1] + t * gv[1];
    g[2] = g0[2] + t * gv[2];
  }
};

/// What a pixel accumulates (premultiplied colour in 0-255 units, opacity).
struct Acc {
  float C[3] = {0, 0, 0};
  float A = 0;
};

/// The first sample at or past where the ray leaves the region of side 2^shift (in cell-corner
/// space) holding corner `c` (>> shift), or k_end; never before k + 1.
inline std::int64_t region_exit(const RayGrid& r, std::int64_t k, std::int64_t k_end, const int c[3], int shift,
                                const int n[3]) {
  double t_exit = kInf;
  for (int a = 0; a < 3; ++a) {
    if (r.gv[a] > 0) {
      const int plane = (c[a] + 1) << shift;
      if (plane <= n[a] - 2) t_exit = std::min(t_exit, (plane - r.g0[a]) * r.inv_gv[a]);
    } else if (r.gv[a] < 0) {
      if (c[a] > 0) t_exit = std::min(t_exit, ((c[a] << shift) - r.g0[a]) * r.inv_gv[a]);
    }
  }
  if (t_exit == kInf) return k_end;
  const double q = std::ceil((t_exit - r.a) / r.h);
  if (!(q < double(k_end))) return k_end;
  return std::max(k + 1, std::int64_t(std::max(q, 0.0)));
}

/// How far an empty region may be skipped: back off until sample k2 - 1 is still in the region
/// (the samples in a box are consecutive, so then all of k .. k2 - 1 are), so no sample outside the
/// dead region is ever skipped, whatever the rounding of the exit.
inline std::int64_t verified_skip(const RayGrid& r, std::int64_t k, std::int64_t k2, const int c[3], int shift,
                                  const int n[3]) {
  while (k2 - 1 > k) {
    double g[3];
    r.at(k2 - 1, g);
    const Loc L = locate(g, n);
    if ((L.i[0] >> shift) == c[0] && (L.i[1] >> shift) == c[1] && (L.i[2] >> shift) == c[2]) break;
    --k2;
  }
  return k2;
}

/// Counters of one segment.
struct SegmentCount {
  std::int64_t taken = 0, skipped = 0;
  bool terminated = false;
};

/// The model: TF lookup, shading, compositing, and the traversal of one ray segment k ∈ [k0, k1).
template <class T>
struct TfKernel {
  Store<T> store;
  const EmptySpace* ess = nullptr;  // null: no skipping
  EmptySpaceScheme scheme = EmptySpaceScheme::kMultiLevel;
  struct Range {
    double lo, hi;
    bool lo_closed, hi_closed;
    float rgb[3];
    float alpha;  // corrected for the step
  };
  std::vector<Range> ranges;
  bool ert = false;
  float ert_threshold = 2;  // A > this stops the ray
  bool shade = false;
  bool central = true;
  float grad_threshold2 = 4;
  float light[3] = {0, 0, 0};  // L (propagation)
  float ka = 0.16f, ks = 120, q = 128;
  int q_whole = 128;  // q as a whole number (<= 4096), or -1
  float inv_spacing[3] = {1, 1, 1};

  [[gnu::always_inline]] int find(float f) const {
    const double v = f;
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const Range& R = ranges[i];
      if ((R.lo_closed ? v >= R.lo : v > R.lo) && (R.hi_closed ? v <= R.hi : v < R.hi)) return int(i);
    }
    return -1;
  }

  /// The gradient at a located sample (value per voxel): central differences at offset 1 of the
  /// trilinear interpolant, (P(x + 1) - P(x - 1)) / 2 per axis, or the repo's one-sided P(x) - P(x + 1);
  /// voxel indices clamped to the volume. The shifted lookups share the sample's weights, so they
  /// read the 32 voxels around its cell through the offset tables (any layout) and blend them.
  void gradient(const Loc& L, float f, float grad[3]) const {
    std::int64_t o[3][4];
    for (int a = 0; a < 3; ++a)
      for (int d = 0; d < 4; ++d) o[a][d] = store.off[a][std::size_t(std::clamp(L.i[a] - 1 + d, 0, store.n[a] - 1))];
    const T* p = store.data;
    auto v = [&](int x, int y, int z) { return static_cast<float>(p[o[0][x] + o[1][y] + o[2][z]]); };
    // The blend with the cell's lower corner at (x, y, z) of the 4-wide index sets (1 = the sample's own).
    auto P = [&](int x, int y, int z) {
      const float c00 = lerp(v(x, y, z), v(x + 1, y, z), L.t[0]);
      const float c10 = lerp(v(x, y + 1, z), v(x + 1, y + 1, z), L.t[0]);
      const float c01 = lerp(v(x, y, z + 1), v(x + 1, y, z + 1), L.t[0]);
      const float c11 = lerp(v(x, y + 1, z + 1), v(x + 1, y + 1, z + 1), L.t[0]);
      const float r = lerp(lerp(c00, c10, L.t[1]), lerp(c01, c11, L.t[1]), L.t[2]);
      return store.unit_scale ? r : r * store.scale;
    };
    if (central) {
      grad[0] = (P(2, 1, 1) - P(0, 1, 1)) * 0.5f;  // points into dense material
      grad[1] = (P(1, 2, 1) - P(1, 0, 1)) * 0.5f;
      grad[2] = (P(1, 1, 2) - P(1, 1, 0)) * 0.5f;
    } else {
      grad[0] = f - P(2, 1, 1);  // the repo: already outward
      grad[1] = f - P(1, 2, 1);
      grad[2] = f - P(1, 1, 2);
    }
  }

  /// x^q: by squaring for a whole q (the repo's 128: seven multiplications), else powf.
  float power(float x) const {
    if (q_whole < 0) return std::pow(x, q);
    float r = 1, b = x;
    for (int e = q_whole; e > 0; e >>= 1) {
      if (e & 1) r *= b;
      b *= b;
    }
    return r;
  }

  /// Phong: c' = c (max(n̂ · -L, 0) + ka) + ks max(r · v₋, 0)^q where |∇f| > threshold.
  void shade_colour(const Loc& L, float f, const RayGrid& ray, float c[3]) const {
    float grad[3];
    gradient(L, f, grad);
    const float g2 = grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2];
    if (!(g2 > grad_threshold2)) return;
    // The outward normal in world space (the gradient per scene unit).
    float nrm[3];
    for (int a = 0; a < 3; ++a) nrm[a] = (central ? -grad[a] : grad[a]) * inv_spacing[a];
    const float len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    if (!(len > 0)) return;
    for (float& x : nrm) x /= len;
    const float nl = nrm[0] * light[0] + nrm[1] * light[1] + nrm[2] * light[2];
    const float diffuse = std::max(-nl, 0.0f);
    float rv = 0;
    for (int a = 0; a < 3; ++a) rv += (light[a] - 2 * nl * nrm[a]) * ray.view[a];
    const float spec = rv > 0 ? ks * power(rv) : 0.0f;
    for (int a = 0; a < 3; ++a) c[a] = c[a] * (diffuse + ka) + spec;
  }

  /// One located sample composited into acc; false when the ray terminates.
  [[gnu::always_inline]] bool sample(const Loc& L, const RayGrid& ray, Acc& acc) const {
    const float f = store.fetch(L);
    const int r = find(f);
    if (r < 0) return true;
    const Range& R = ranges[std::size_t(r)];
    if (!(R.alpha > 0)) return true;
    float c[3] = {R.rgb[0], R.rgb[1], R.rgb[2]};
    if (shade) shade_colour(L, f, ray, c);
    const float w = R.alpha * (1.0f - acc.A);
    acc.C[0] += c[0] * w;
    acc.C[1] += c[1] * w;
    acc.C[2] += c[2] * w;
    acc.A += w;
    return !(ert && acc.A > ert_threshold);
  }

  /// The samples k ∈ [k, k_end) of the ray, composited into acc (stops early on ERT).
  SegmentCount segment(const RayGrid& ray, std::int64_t k, std::int64_t k_end, Acc& acc) const {
    SegmentCount cnt;
    const int* n = store.n;
    double g[3];
    if (!ess) {
      for (; k < k_end; ++k) {
        ray.at(k, g);
        ++cnt.taken;
        if (!sample(locate(g, n), ray, acc)) {
          cnt.terminated = true;
          return cnt;
        }
      }
    } else if (scheme == EmptySpaceScheme::kOneLevel) {
      // The source: every sample's cell looked up; an empty one costs a step.
      for (; k < k_end; ++k) {
        ray.at(k, g);
        const Loc L = locate(g, n);
        if (!ess->cell_live(L)) {
          ++cnt.skipped;
          continue;
        }
        ++cnt.taken;
        if (!sample(L, ray, acc)) {
          cnt.terminated = true;
          return cnt;
        }
      }
    } else {
      // Multi-level: a dead 32³ region or 4³ cell is crossed in one jump; a live cell is sampled
      // to its exit without further lookups.
      while (k < k_end) {
        ray.at(k, g);
        Loc L = locate(g, n);
        if (!ess->region_live(L)) {
          const int c[3] = {L.i[0] >> kRegionShift, L.i[1] >> kRegionShift, L.i[2] >> kRegionShift};
          const std::int64_t k2 =
              verified_skip(ray, k, region_exit(ray, k, k_end, c, kRegionShift, n), c, kRegionShift, n);
          cnt.skipped += k2 - k;
          k = k2;
          continue;
        }
        const int c[3] = {L.i[0] >> kCellShift, L.i[1] >> kCellShift, L.i[2] >> kCellShift};
        if (!ess->cell_live(L)) {
          const std::int64_t k2 = verified_skip(ray, k, region_exit(ray, k, k_end, c, kCellShift, n), c, kCellShift, n);
          cnt.skipped += k2 - k;
          k = k2;
          continue;
        }
        const std::int64_t run_end = region_exit(ray, k, k_end, c, kCellShift, n);
        for (;;) {
          ++cnt.taken;
          if (!sample(L, ray, acc)) {
            cnt.terminated = true;
            return cnt;
          }
          if (++k >= run_end) break;
          ray.at(k, g);
          L = locate(g, n);
        }
      }
    }
    return cnt;
  }
};

// ---- the state ----------------------------------------------------------------------------------

/// The part of a tracer every sample type shares: geometry and settings.
struct TfGeometry {
  Box3 box;
  Vec3 origin, inv_spacing;
  double ds = 0;
};

template <class T>
class TfState final : public TracerState {
 public:
  TfState(const VolumeRenderSettings& s, Store<T> store, const TfGeometry& geo,
          std::shared_ptr<const RangeIndex<T>> ranges, const BrickedVolume* bricked, std::shared_ptr<const void> keep)
      : s_(s), geo_(geo), keep_(std::move(keep)) {
    box = geo.box;
    if (bricked) bricked_ = *bricked;
    k_.store = std::move(store);
    // The TF with its opacities corrected for the step.
    const double s0 = s.tf.reference_step > 0 ? s.tf.reference_step : 1.0 / geo.inv_spacing.maxCoeff();
    for (const TfRange& r : s.tf.table.ranges()) {
      typename TfKernel<T>::Range R{};
      R.lo = r.lo, R.hi = r.hi, R.lo_closed = r.lo_closed, R.hi_closed = r.hi_closed;
      for (int c = 0; c < 3; ++c) R.rgb[c] = float(r.rgb[c]);
      R.alpha = float(corrected_opacity(r.alpha, geo.ds, s0, s.tf.exponent));
      k_.ranges.push_back(R);
    }
    k_.ert = s.ert_transmittance > 0;
    k_.ert_threshold = float(1.0 - s.ert_transmittance);
    k_.shade = s.tf.shading.enabled;
    k_.central = s.tf.shading.gradient == GradientScheme::kCentral;
    k_.grad_threshold2 = float(s.tf.shading.threshold * s.tf.shading.threshold);
    const Vec3 L = s.tf.shading.light_dir.normalized();
    for (int a = 0; a < 3; ++a) {
      k_.light[a] = float(L[a]);
      k_.inv_spacing[a] = float(geo.inv_spacing[a]);
    }
    k_.ka = float(s.tf.shading.ka);
    k_.ks = float(s.tf.shading.ks);
    k_.q = float(s.tf.shading.q);
    k_.q_whole = s.tf.shading.q == std::floor(s.tf.shading.q) && s.tf.shading.q <= 4096 ? int(s.tf.shading.q) : -1;
    // Empty space: the flags of this TF from the (shared) ranges.
    if (s.skip_empty) {
      const auto t0 = std::chrono::steady_clock::now();
      if (!ranges) {
        auto built = build_cell_ranges(k_.store);
        if (bricked) add_block_ranges(*built, *bricked);
        ranges = built;
      }
      ranges_ = ranges;
      ess_ = build_empty_space(k_.store, *ranges_, s.tf.table, s.ess_test, bricked ? &bricked_ : nullptr);
      k_.ess = &ess_;
      k_.scheme = s.ess;
      index_ms = ms_since(t0);
    }
  }

  double trace(const Vec3& o, const Vec3& v, double t0, double t1, std::uint64_t pixel, Rgb& I,
               VolumeRenderStats& st) const override {
    const RayGrid ray = make_ray(o, v, t0, t1, pixel);
    Acc acc;
    const SegmentCount c = k_.segment(ray, 0, ray.n, acc);
    st.samples += c.taken;
    st.skipped += c.skipped;
    if (c.terminated) ++st.terminated;
    I += Rgb(acc.C[0], acc.C[1], acc.C[2]) / 255.0;
    return 1.0 - double(acc.A);
  }

  /// The opacity along the ray as an optical depth, -ln(1 - A) (colour ignored).
  double optical_depth(const Vec3& x, const Vec3& d, double max_distance, std::int64_t& samples) const override {
    const auto hit = intersect_box(geo_.box, x, d);
    if (!hit) return 0;
    const double t0 = std::max(hit->t0, 0.0), t1 = std::min(hit->t1, max_distance);
    if (!(t1 > t0)) return 0;
    VolumeRenderStats st;
    Rgb I = Rgb::Zero();
    const double trans = trace(x, d, t0, t1, 0, I, st);
    samples += st.samples;
    return -std::log(std::max(trans, 1e-300));
  }

  std::optional<VolumeFrame> render(const Camera& camera) const override {
    if (s_.traversal == Traversal::kObjectOrder) return render_object_order(camera);
    return render_image_order(camera);
  }

 private:
  RayGrid make_ray(const Vec3& o, const Vec3& v, double t0, double t1, std::uint64_t pixel) const {
    const SampleGrid sg = detail::sample_grid(s_, geo_.ds, t0, t1, pixel);
    RayGrid r;
    const Vec3 go = (o - geo_.origin).cwiseProduct(geo_.inv_spacing);
    const Vec3 gd = v.cwiseProduct(geo_.inv_spacing);
    for (int a = 0; a < 3; ++a) {
      r.g0[a] = go[a];
      r.gv[a] = gd[a];
      r.inv_gv[a] = 1.0 / gd[a];
      r.view[a] = float(-v[a]);
    }
    r.a = sg.a;
    r.h = sg.h;
    r.n = sg.n;
    return r;
  }

  /// The pixels whose rays can meet the volume: its box projected (clv.camera: canvas restriction).
  PixelWindow canvas(const Camera& camera, const RayGenerator& gen) const {
    const int W = camera_width(camera), H = camera_height(camera);
    PixelWindow all{0, 0, W, H};
    if (!s_.restrict_canvas) return all;
    Vec2d lo = Vec2d::Constant(kInf), hi = Vec2d::Constant(-kInf);
    for (int c = 0; c < 8; ++c) {
      const Vec3 p(c & 1 ? box.hi.x() : box.lo.x(), c & 2 ? box.hi.y() : box.lo.y(), c & 4 ? box.hi.z() : box.lo.z());
      const Projection pr = gen.project(p);
      if (!pr.in_front || !pr.pixel.allFinite()) return all;  // the box reaches behind the eye
      lo = lo.cwiseMin(pr.pixel);
      hi = hi.cwiseMax(pr.pixel);
    }
    // One pixel of margin: a ray through a pixel centre just outside the hull can still graze the box.
    const int x0 = std::max(0, int(std::floor(lo.x())) - 1), y0 = std::max(0, int(std::floor(lo.y())) - 1);
    const int x1 = std::min(W, int(std::ceil(hi.x())) + 2), y1 = std::min(H, int(std::ceil(hi.y())) + 2);
    if (x1 <= x0 || y1 <= y0) return PixelWindow{0, 0, 0, 0};
    return PixelWindow{x0, y0, x1 - x0, y1 - y0};
  }

  void check_eye(const Camera& camera) const {
    if (const auto* pin = std::get_if<Pinhole>(&camera)) {
      const Vec3 eye = pin->camera_from_world.inverse().translation();
      if (box.contains(eye) && s_.camera_inside == CameraInside::kReject)
        throw InputError(
            "volume render: the camera is inside the volume's box (vlr.camera.inside: reject); move it out or set "
            "camera_inside: start_at_eye");
    }
  }

  /// What both traversals start a frame with: a blank frame (the eye checked), the rays, the
  /// canvas, and the clock.
  struct FrameStart {
    FrameStart(const TfState& tracer, const Camera& camera)
        : frame(tracer.blank_frame(camera)),
          width(camera_width(camera)),
          gen(camera),
          win(tracer.canvas(camera, gen)),
          t_render(std::chrono::steady_clock::now()) {}
    VolumeFrame frame;
    int width;
    RayGenerator gen;
    PixelWindow win;
    std::chrono::steady_clock::time_point t_render;
  };

  /// A frame of no light yet, for a camera whose eye check_eye accepts.
  VolumeFrame blank_frame(const Camera& camera) const {
    check_eye(camera);
    VolumeFrame f;
    const int W = camera_width(camera), H = camera_height(camera);
    f.radiance = ImageF(W, H, 3, 0.0f);
    f.transmittance = ImageF(W, H, 1, 1.0f);
    if (s_.record_sample_counts) f.sample_counts.assign(std::size_t(W) * std::size_t(H), 0);
    return f;
  }

  static void write_pixel(VolumeFrame& f, int x, int y, const Acc& acc) {
    float* rad = f.radiance.row(y) + 3 * x;
    rad[0] = acc.C[0] / 255.0f;
    rad[1] = acc.C[1] / 255.0f;
    rad[2] = acc.C[2] / 255.0f;
    f.transmittance.at(x, y) = 1.0f - acc.A;
  }

  // ---- image order ----

  VolumeFrame render_image_order(const Camera& camera) const {
    FrameStart start(*this, camera);
    auto& [frame, W, gen, win, t_render] = start;
    tbb::combinable<VolumeRenderStats> stats;
    auto rows = [&](int y0, int y1, int x0, int x1) {
      VolumeRenderStats& st = stats.local();
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const CameraRay cr = gen.generate_ray(x, y);
          if (!cr.ok) continue;
          const auto hit = intersect_box(box, cr.origin, cr.direction);
          if (!hit) continue;
          const std::size_t p = std::size_t(y) * std::size_t(W) + std::size_t(x);
          const RayGrid ray = make_ray(cr.origin, cr.direction, std::max(hit->t0, 0.0), hit->t1, p);
          ++st.rays;
          Acc acc;
          const SegmentCount c = k_.segment(ray, 0, ray.n, acc);
          st.samples += c.taken;
          st.skipped += c.skipped;
          if (c.terminated) ++st.terminated;
          write_pixel(frame, x, y, acc);
          if (!frame.sample_counts.empty()) frame.sample_counts[p] = std::uint32_t(c.taken);
        }
    };
    if (s_.parallel) {
      constexpr int kTile = 16;
      tbb::parallel_for(tbb::blocked_range2d<int>(win.y, win.y + win.height, kTile, win.x, win.x + win.width, kTile),
                        [&](const tbb::blocked_range2d<int>& r) {
                          rows(r.rows().begin(), r.rows().end(), r.cols().begin(), r.cols().end());
                        });
    } else {
      rows(win.y, win.y + win.height, win.x, win.x + win.width);
    }
    stats.combine_each([&](const VolumeRenderStats& st) {
      frame.stats.rays += st.rays;
      frame.stats.samples += st.samples;
      frame.stats.skipped += st.skipped;
      frame.stats.terminated += st.terminated;
    });
    frame.stats.render_ms = ms_since(t_render);
    return std::move(frame);  // (a member of start: moved, not copied)
  }

  // ---- object order (seed 001 §2.8) ----

  struct PixelRay {
    RayGrid ray;
    Acc acc;
    std::int64_t next_k = 0;  // the first sample not yet composited (visibility-order check)
    std::int64_t taken = 0;
    int x = 0, y = 0;
    bool met = false, terminated = false;
  };
  struct Tile {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    std::vector<PixelRay> px;
    std::vector<std::uint32_t> blocks;  // near to far
    std::size_t next = 0;
  };
  struct Task {
    Tile* tile;
    std::uint32_t block;
  };

  /// Whether sample k of the ray lies in block b's cells (its owned corners, [lo, hi) per axis).
  static bool owned(const RayGrid& r, std::int64_t k, const int lo[3], const int hi[3], const int n[3]) {
    double g[3];
    r.at(k, g);
    const Loc L = locate(g, n);
    return L.i[0] >= lo[0] && L.i[0] < hi[0] && L.i[1] >= lo[1] && L.i[1] < hi[1] && L.i[2] >= lo[2] && L.i[2] < hi[2];
  }

  /// The block's samples of the ray: [k0, k1), exactly those whose cell the block owns.
  static void block_samples(const RayGrid& r, const int lo[3], const int hi[3], const int n[3], std::int64_t& k0,
                            std::int64_t& k1) {
    // The slab test in index space against the owned box widened by a voxel (rounding), then exact
    // ownership at both ends (the owned samples of a box are consecutive).
    double t0 = -kInf, t1 = kInf;
    for (int a = 0; a < 3; ++a) {
      const double blo = lo[a] - 1.0, bhi = hi[a] + 1.0;
      if (r.gv[a] == 0) {
        if (r.g0[a] < blo || r.g0[a] > bhi) {
          k0 = k1 = 0;
          return;
        }
        continue;
      }
      double tn = (blo - r.g0[a]) * r.inv_gv[a], tf = (bhi - r.g0[a]) * r.inv_gv[a];
      if (tn > tf) std::swap(tn, tf);
      t0 = std::max(t0, tn);
      t1 = std::min(t1, tf);
    }
    if (t0 > t1) {
      k0 = k1 = 0;
      return;
    }
    const double q0 = std::floor((t0 - r.a) / r.h), q1 = std::ceil((t1 - r.a) / r.h) + 1;
    k0 = std::int64_t(std::clamp(q0, 0.0, double(r.n)));
    k1 = std::int64_t(std::clamp(q1, 0.0, double(r.n)));
    while (k0 < k1 && !owned(r, k0, lo, hi, n)) ++k0;
    while (k1 > k0 && !owned(r, k1 - 1, lo, hi, n)) --k1;
    if (k0 == k1) return;
    while (k0 > 0 && owned(r, k0 - 1, lo, hi, n)) --k0;
    while (k1 < r.n && owned(r, k1, lo, hi, n)) ++k1;
  }

  VolumeFrame render_object_order(const Camera& camera) const {
    FrameStart start(*this, camera);
    auto& [frame, W, gen, win, t_render] = start;
    const int side = s_.tile;
    const int n[3] = {bricked_.nx(), bricked_.ny(), bricked_.nz()};
    const auto nb = bricked_.blocks();
    const int stride = bricked_.side() - 1;
    // Tiles over the canvas, each with its pixels' rays (computed once per frame, in parallel).
    const int tx = (win.width + side - 1) / side, ty = (win.height + side - 1) / side;
    std::vector<Tile> tiles(std::size_t(tx) * std::size_t(ty));
    tbb::parallel_for(0, int(tiles.size()), [&](int ti) {
      Tile& t = tiles[std::size_t(ti)];
      t.x0 = win.x + (ti % tx) * side;
      t.y0 = win.y + (ti / tx) * side;
      t.x1 = std::min(win.x + win.width, t.x0 + side);
      t.y1 = std::min(win.y + win.height, t.y0 + side);
      t.px.resize(std::size_t(t.x1 - t.x0) * std::size_t(t.y1 - t.y0));
      std::size_t i = 0;
      for (int y = t.y0; y < t.y1; ++y)
        for (int x = t.x0; x < t.x1; ++x, ++i) {
          PixelRay& p = t.px[i];
          p.x = x;
          p.y = y;
          const CameraRay cr = gen.generate_ray(x, y);
          if (!cr.ok) continue;
          const auto hit = intersect_box(box, cr.origin, cr.direction);
          if (!hit) continue;
          p.ray = make_ray(cr.origin, cr.direction, std::max(hit->t0, 0.0), hit->t1,
                           std::size_t(y) * std::size_t(W) + std::size_t(x));
          p.met = true;
        }
    });
    // build_queues: visible blocks, near to far by centre distance (clv.par.sort_key; the distance
    // along the ray for an orthographic camera), each into the queues of the tiles its projected
    // rectangle meets.
    struct Queued {
      double dist;
      std::uint32_t block;
    };
    std::vector<Queued> order;
    order.reserve(std::size_t(bricked_.block_count()));
    for (int bx = 0; bx < nb[0]; ++bx)
      for (int by = 0; by < nb[1]; ++by)
        for (int bz = 0; bz < nb[2]; ++bz) {
          const std::uint32_t id = std::uint32_t((std::int64_t(bx) * nb[1] + by) * nb[2] + bz);
          if (k_.ess && !ess_.block_live[id]) continue;  // ESS: invisible blocks are never queued
          const Vec3 c =
              geo_.origin + Vec3(bx * stride + 0.5 * stride, by * stride + 0.5 * stride, bz * stride + 0.5 * stride)
                                .cwiseQuotient(geo_.inv_spacing);
          order.push_back({gen.project(c).distance, id});
        }
    tbb::parallel_sort(order.begin(), order.end(), [](const Queued& a, const Queued& b) {
      return a.dist < b.dist || (a.dist == b.dist && a.block < b.block);
    });
    for (const Queued& q : order) {
      const int bz = int(q.block % std::uint32_t(nb[2])),
                by = int((q.block / std::uint32_t(nb[2])) % std::uint32_t(nb[1])),
                bx = int(q.block / std::uint32_t(nb[2]) / std::uint32_t(nb[1]));
      // The projected rectangle of the block's box (its owned voxels).
      const int lo[3] = {bx * stride, by * stride, bz * stride};
      Vec2d plo = Vec2d::Constant(kInf), phi = Vec2d::Constant(-kInf);
      bool behind = false;
      for (int c = 0; c < 8; ++c) {
        Vec3 gidx;
        for (int a = 0; a < 3; ++a) gidx[a] = std::min(double(lo[a] + ((c >> a) & 1 ? stride : 0)), double(n[a] - 1));
        const Projection pr = gen.project(geo_.origin + gidx.cwiseQuotient(geo_.inv_spacing));
        if (!pr.in_front || !pr.pixel.allFinite()) {
          behind = true;
          break;
        }
        plo = plo.cwiseMin(pr.pixel);
        phi = phi.cwiseMax(pr.pixel);
      }
      int px0 = win.x, py0 = win.y, px1 = win.x + win.width - 1, py1 = win.y + win.height - 1;
      if (!behind) {
        px0 = std::max(px0, int(std::floor(plo.x())) - 1);
        py0 = std::max(py0, int(std::floor(plo.y())) - 1);
        px1 = std::min(px1, int(std::ceil(phi.x())) + 1);
        py1 = std::min(py1, int(std::ceil(phi.y())) + 1);
      }
      if (px1 < px0 || py1 < py0) continue;
      for (int ty_i = (py0 - win.y) / side; ty_i <= (py1 - win.y) / side; ++ty_i)
        for (int tx_i = (px0 - win.x) / side; tx_i <= (px1 - win.x) / side; ++tx_i)
          tiles[std::size_t(ty_i) * std::size_t(tx) + std::size_t(tx_i)].blocks.push_back(q.block);
    }
    frame.stats.blocks_visible = std::int64_t(order.size());

    // One render task per tile in flight: the render node (render_threads at a time) composites a
    // block into a tile and hands the tile back; the serial compositor node sends the tile's next
    // block or, when its queue is empty, copies the tile into the frame. A tile is owned by whoever
    // holds its pointer (a task in flight, or the compositor), so its buffers need no lock.
    struct ThreadStats {
      VolumeRenderStats st;
      double busy_ms = 0;
    };
    tbb::enumerable_thread_specific<ThreadStats> tstats;
    std::atomic<std::int64_t> pending{0}, queue_empty{0}, tasks{0};
    const int threads =
        s_.render_threads > 0 ? s_.render_threads : int(std::max(1u, std::thread::hardware_concurrency()));
    auto render_task = [&](const Task& task) {
      const auto t0 = std::chrono::steady_clock::now();
      pending.fetch_sub(1, std::memory_order_relaxed);
      ThreadStats& ts = tstats.local();
      const std::uint32_t id = task.block;
      const int bz = int(id % std::uint32_t(nb[2])), by = int((id / std::uint32_t(nb[2])) % std::uint32_t(nb[1])),
                bx = int(id / std::uint32_t(nb[2]) / std::uint32_t(nb[1]));
      const int lo[3] = {bx * stride, by * stride, bz * stride};
      const int hi[3] = {std::min(lo[0] + stride, n[0] - 1), std::min(lo[1] + stride, n[1] - 1),
                         std::min(lo[2] + stride, n[2] - 1)};
      for (PixelRay& p : task.tile->px) {
        if (!p.met || p.terminated) continue;  // global ERT
        std::int64_t k0 = 0, k1 = 0;
        block_samples(p.ray, lo, hi, n, k0, k1);
        if (k0 >= k1) continue;
        if (k0 < p.next_k) ++ts.st.order_violations;
        const SegmentCount c = k_.segment(p.ray, k0, k1, p.acc);
        p.taken += c.taken;
        p.next_k = k1;
        ts.st.samples += c.taken;
        ts.st.skipped += c.skipped;
        if (c.terminated) {
          p.terminated = true;
          ++ts.st.terminated;
        }
      }
      ++ts.st.block_tasks;
      if (pending.load(std::memory_order_relaxed) == 0) queue_empty.fetch_add(1, std::memory_order_relaxed);
      ts.busy_ms += ms_since(t0);
      return task.tile;
    };
    auto finish_tile = [&](Tile& t) {
      for (const PixelRay& p : t.px) {
        if (!p.met) continue;
        write_pixel(frame, p.x, p.y, p.acc);
        if (!frame.sample_counts.empty())
          frame.sample_counts[std::size_t(p.y) * std::size_t(W) + std::size_t(p.x)] = std::uint32_t(p.taken);
      }
    };
    // More render threads than the machine has (the thread-count sweep) need TBB's permission.
    std::optional<tbb::global_control> allow;
    if (threads > int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism)))
      allow.emplace(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::flow::graph g;
      tbb::flow::function_node<Task, Tile*> render_node(g, std::size_t(threads), render_task);
      tbb::flow::function_node<Tile*, tbb::flow::continue_msg> compositor(g, tbb::flow::serial, [&](Tile* t) {
        if (t->next < t->blocks.size()) {
          pending.fetch_add(1, std::memory_order_relaxed);
          tasks.fetch_add(1, std::memory_order_relaxed);
          render_node.try_put(Task{t, t->blocks[t->next++]});
        } else {
          finish_tile(*t);
        }
        return tbb::flow::continue_msg{};
      });
      tbb::flow::make_edge(render_node, compositor);
      for (Tile& t : tiles) {
        if (t.blocks.empty()) {
          finish_tile(t);
          continue;
        }
        pending.fetch_add(1, std::memory_order_relaxed);
        tasks.fetch_add(1, std::memory_order_relaxed);
        render_node.try_put(Task{&t, t.blocks[t.next++]});
      }
      g.wait_for_all();
    });
    for (const Tile& t : tiles)
      for (const PixelRay& p : t.px) frame.stats.rays += p.met ? 1 : 0;
    for (const ThreadStats& ts : tstats) {
      frame.stats.samples += ts.st.samples;
      frame.stats.skipped += ts.st.skipped;
      frame.stats.terminated += ts.st.terminated;
      frame.stats.block_tasks += ts.st.block_tasks;
      frame.stats.order_violations += ts.st.order_violations;
      frame.stats.render_busy_ms += ts.busy_ms;
    }
    frame.stats.queue_empty = queue_empty.load();
    frame.stats.render_ms = ms_since(t_render);
    return std::move(frame);  // (a member of start: moved, not copied)
  }

  VolumeRenderSettings s_;
  TfGeometry geo_;
  std::shared_ptr<const void> keep_;  // the volume's samples
  BrickedVolume bricked_;
  TfKernel<T> k_;
  std::shared_ptr<const RangeIndex<T>> ranges_;
  EmptySpace ess_;
};

template <class T>
std::shared_ptr<const RangeIndex<T>> typed_ranges(const std::shared_ptr<const VolumeRangeIndex>& r,
                                                  const std::array<int, 3>& dims, bool need_blocks) {
  if (!r) return nullptr;
  auto typed = std::dynamic_pointer_cast<const RangeIndex<T>>(r);
  if (!typed || r->dims() != dims || (need_blocks && typed->block_min.empty()))
    throw InputError("volume render: the range index was built for another volume");
  return typed;
}

TfGeometry geometry_of(const Box3& domain, const Vec3& origin, const Vec3& spacing, const VolumeRenderSettings& s) {
  TfGeometry g;
  g.box = domain;
  g.origin = origin;
  g.inv_spacing = spacing.cwiseInverse();
  g.ds = s.step_rule == StepRule::kDiagonalOverN ? domain.diagonal() / s.samples : s.step;
  return g;
}

void check_dims(const std::array<int, 3>& d) {
  if (d[0] < 2 || d[1] < 2 || d[2] < 2)
    throw InputError(fmt::format(
        "volume render: the transfer_function model needs at least 2 samples per axis (the volume is {} x {} x {})",
        d[0], d[1], d[2]));
}

}  // namespace

namespace detail {

void validate_tf(const VolumeRenderSettings& s, bool bricked) {
  auto bad = [](const std::string& what) { throw InputError("volume render: " + what); };
  if (s.step_rule == StepRule::kFitSegment)
    bad("the transfer_function model needs one step for every ray (ds_rule fixed_step or diag_over_n)");
  if (s.include_last_partial) bad("the transfer_function model composites whole steps (last_partial: drop)");
  if (s.address != VolumeAddress::kClamp) bad("the transfer_function model reads with clamp addressing");
  if (!(s.tf.reference_step >= 0 && std::isfinite(s.tf.reference_step)))
    bad("the TF's reference step must be finite and >= 0 (0: one voxel)");
  const TfShading& sh = s.tf.shading;
  if (!(sh.threshold >= 0 && std::isfinite(sh.threshold)))
    bad("the shading's gradient threshold must be finite and >= 0");
  if (!(sh.light_dir.allFinite() && sh.light_dir.norm() > 0)) bad("the shading's light direction must be non-zero");
  if (!(sh.ka >= 0 && sh.ks >= 0 && sh.q >= 0 && std::isfinite(sh.ka) && std::isfinite(sh.ks) && std::isfinite(sh.q)))
    bad("the shading's ka, ks and q must be finite and >= 0");
  if (s.tf.table.ranges().size() > 64) bad("a transfer function has at most 64 ranges");
  if (s.tf.table.kind() != TfKind::kPiecewiseConstant)
    bad("the ray caster's transfer_function model reads piecewise-constant TFs (piecewise-linear ones: method: "
        "slicing)");
  if (s.tile < 1 || s.tile > 4096) bad(fmt::format("the tile side must be in [1, 4096] (got {})", s.tile));
  if (s.render_threads < 0 || s.render_threads > 1024)
    bad(fmt::format("the render thread count must be in [0, 1024] (got {})", s.render_threads));
  if (s.traversal == Traversal::kObjectOrder && !bricked)
    bad("the object-order traversal needs a bricked volume (a .clv file in blocks, or volume.layout: blocked)");
}

std::unique_ptr<TracerState> make_tf_state(const Volume& volume, const VolumeRenderSettings& s,
                                           std::shared_ptr<const VolumeRangeIndex> ranges) {
  check_dims(volume.dims());
  const TfGeometry geo = geometry_of(volume.domain(), volume.origin(), volume.spacing(), s);
  return visit_samples(volume, [&](const auto& vs) -> std::unique_ptr<TracerState> {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(vs.data)>>;
    // The volume (a copy sharing its samples) is kept alive by the state.
    auto keep = std::make_shared<Volume>(volume);
    return std::make_unique<TfState<T>>(s, dense_store<T>(volume), geo, typed_ranges<T>(ranges, volume.dims(), false),
                                        nullptr, keep);
  });
}

std::unique_ptr<TracerState> make_tf_state(const BrickedVolume& volume, const VolumeRenderSettings& s,
                                           std::shared_ptr<const VolumeRangeIndex> ranges) {
  check_dims(volume.dims());
  const TfGeometry geo = geometry_of(volume.domain(), volume.origin(), volume.spacing(), s);
  return visit_samples(volume, [&](const auto& bs) -> std::unique_ptr<TracerState> {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(bs.data)>>;
    return std::make_unique<TfState<T>>(s, brick_store<T>(volume), geo, typed_ranges<T>(ranges, volume.dims(), true),
                                        &volume, nullptr);
  });
}

}  // namespace detail

std::shared_ptr<const VolumeRangeIndex> VolumeRangeIndex::build(const Volume& volume) {
  check_dims(volume.dims());
  return visit_samples(volume, [&](const auto& vs) -> std::shared_ptr<const VolumeRangeIndex> {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(vs.data)>>;
    return build_cell_ranges(dense_store<T>(volume));
  });
}

std::shared_ptr<const VolumeRangeIndex> VolumeRangeIndex::build(const BrickedVolume& volume) {
  check_dims(volume.dims());
  return visit_samples(volume, [&](const auto& bs) -> std::shared_ptr<const VolumeRangeIndex> {
    using T = std::remove_cv_t<std::remove_pointer_t<decltype(bs.data)>>;
    auto ix = build_cell_ranges(brick_store<T>(volume));
    add_block_ranges(*ix, volume);
    return ix;
  });
}

Image8 tf_output_image(const VolumeFrame& frame, TfOutput output) {
  const int W = frame.radiance.width(), H = frame.radiance.height();
  Image8 out(W, H, 3);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const float A = 1.0f - frame.transmittance.at(x, y);
      for (int c = 0; c < 3; ++c) {
        // C in 0-255 units (the frame holds C/255; 1e-4 absorbs that division's rounding so a whole
        // C truncates to itself), times A for the source's double multiply; truncated, as the source.
        double v = double(frame.radiance.at(x, y, c)) * 255.0;
        if (output == TfOutput::kSourceDouble) v *= double(A);
        out.at(x, y, c) = std::uint8_t(std::clamp(std::floor(v + 1e-4), 0.0, 255.0));
      }
    }
  return out;
}

}  // namespace meltlab::render
