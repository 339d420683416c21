// Seed 003's slicing renderer (see slicing/slicing_renderer.h).

#include <meltlab/render/slicing/slicing_renderer.h>

#include "fixed_position.h"
#include "lane_math.h"
#include "ray_setup.h"
#include "packet.h"

// The packets pass 64-byte vectors between inline lambdas of this file only (no ABI crossed).
#pragma GCC diagnostic ignored "-Wpsabi"

#include <meltlab/core/error.h>
#include <meltlab/core/time.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace meltlab::render {

namespace {

/// The bit of voxel (i, j, k) in its brick's word of fetch bits (SlicingRenderer::fetch_bits_).
constexpr int fetch_bit(int i, int j, int k) { return (i & 3) | (j & 3) << 2 | (k & 3) << 4; }

/// Per-tile counters, summed after the frame.
struct TileCounts {
  std::int64_t rays = 0, samples = 0, classified = 0, skipped = 0, terminated = 0, visited = 0, cell_tests = 0;
};

/// A curve of the piecewise-linear kind in float, for the sample's TF (issue 17's thirteenth round):
/// the sample is a float (trilinear in float), so its TF is evaluated in float too — the control
/// points and values rounded to float, y(v) = a.y + t (b.y - a.y), t = (v - a.x) / (b.x - a.x) in
/// float (TfCurve::at's form; within a few 2^-24 of TfCurve::at at the same v), the end values beyond
/// the ends. The differences are those of the rounded points, so v in [a.x, b.x) gives t in [0, 1].
/// One value (InlineTf) and the lanes (LaneLinearTf) share these tables and their arithmetic: a lane
/// computes the scalar's bits.
struct FloatCurve {
  FloatCurve() = default;
  explicit FloatCurve(const TfCurve& c) : n(int(c.points.size())) {
    if (n == 0) return;
    std::vector<float> x, y;
    for (const auto& p : c.points) x.push_back(float(p.x())), y.push_back(float(p.y()));
    x_front = x.front(), y_front = y.front(), x_back = x.back(), y_back = y.back();
    for (int i = 1; i + 1 < n; ++i) interior.push_back(x[std::size_t(i)]);
    for (std::size_t i = 1; i < x.size(); ++i)
      ax.push_back(x[i - 1]), dx.push_back(x[i] - x[i - 1]), ay.push_back(y[i - 1]), dy.push_back(y[i] - y[i - 1]);
  }
  /// Where v falls: i = -1 at or before the first point (NaN included), -2 at or after the last,
  /// else segment i (between points i and i + 1) at t.
  struct Segment {
    int i = -1;
    float t = 0;
  };
  Segment locate(float v) const {
    if (!(v > x_front)) return {-1, 0};
    if (v >= x_back) return {-2, 0};
    std::size_t i = 0;
    while (i < interior.size() && v >= interior[i]) ++i;
    return {int(i), (v - ax[i]) / dx[i]};
  }
  float at(const Segment& s) const {
    if (n == 0) return 0;
    if (s.i == -1) return y_front;
    if (s.i == -2) return y_back;
    return ay[std::size_t(s.i)] + s.t * dy[std::size_t(s.i)];
  }
  int n = 0;
  float x_front = 0, y_front = 0, x_back = 0, y_back = 0;
  std::vector<float> interior, ax, dx, ay, dy;  // interior x; per segment a.x, b.x - a.x, a.y, b.y - a.y
};

/// A TF evaluated without TransferFunction's out-of-line calls: α first, the colour only for visible
/// samples. The constant kind as TransferFunction::alpha_at and ::evaluate do, bit for bit, looked
/// up by "piece": 0 where no range contains the value, i + 1 for the first range i that does (a scan
/// over all ranges; GCC compiles the select to branches, which measured faster than a bitwise
/// branch-free form: 1096 vs 1283 ms on the phantom), and its α and colour (divided by 255 once
/// here, as evaluate divides it per call: the same quotient) read from tables. The linear kind in
/// float (FloatCurve).
class InlineTf {
 public:
  explicit InlineTf(const TransferFunction& tf) : linear_(tf.kind() == TfKind::kPiecewiseLinear) {
    if (linear_) {
      const auto& curves = tf.curves();
      shared_x_ = true;
      for (const auto& c : curves) {
        if (c.points.empty() || c.points.size() != curves[0].points.size()) {
          shared_x_ = false;
          break;
        }
        for (std::size_t i = 0; i < c.points.size(); ++i)
          shared_x_ = shared_x_ && c.points[i].x() == curves[0].points[i].x();
      }
      for (std::size_t c = 0; c < 4; ++c) curves_[c] = FloatCurve(curves[c]);
    } else {
      alpha_.push_back(0.0);
      rgb01_.push_back(Eigen::Vector3f::Zero());
      for (const auto& r : tf.ranges()) {
        lo_.push_back(r.lo), hi_.push_back(r.hi);
        lo_closed_.push_back(r.lo_closed), hi_closed_.push_back(r.hi_closed);
        alpha_.push_back(r.alpha);
        rgb01_.push_back((r.rgb / 255.0).cast<float>());
      }
    }
  }
  bool linear() const { return linear_; }
  /// Pieces of the constant kind, "none" included.
  int pieces() const { return int(alpha_.size()); }
  /// The constant kind's piece of v (0: none): TfRange::contains of each range, the first wins.
  int piece(double v) const {
    int p = 0;
    for (int i = int(lo_.size()) - 1; i >= 0; --i) {
      const std::size_t u = std::size_t(i);
      const bool in = (v > lo_[u] || (lo_closed_[u] && v == lo_[u])) && (v < hi_[u] || (hi_closed_[u] && v == hi_[u]));
      p = in ? i + 1 : p;
    }
    return p;
  }
  double piece_alpha(int p) const { return alpha_[std::size_t(p)]; }
  const Eigen::Vector3f& piece_rgb(int p) const { return rgb01_[std::size_t(p)]; }
  /// The constant kind's ranges (range i is piece i + 1), for the packets' own range tests.
  int ranges() const { return int(lo_.size()); }
  double range_lo(int i) const { return lo_[std::size_t(i)]; }
  double range_hi(int i) const { return hi_[std::size_t(i)]; }
  bool range_lo_closed(int i) const { return lo_closed_[std::size_t(i)] != 0; }
  bool range_hi_closed(int i) const { return hi_closed_[std::size_t(i)] != 0; }
  /// The linear kind's curves (red, green, blue, α) and whether they share their control x (the
  /// `points` rows of a scene: one segment search per sample).
  const std::array<FloatCurve, 4>& curves() const { return curves_; }
  bool shared_x() const { return shared_x_; }
  /// α(v) of the linear kind; `seg` remembers where v fell (on the α curve).
  float alpha(float v, FloatCurve::Segment& seg) const {
    seg = curves_[3].locate(v);
    return curves_[3].at(seg);
  }
  /// The colour of the linear kind (`seg` from alpha(): with shared points, the same segment).
  Eigen::Vector3f rgb(float v, const FloatCurve::Segment& seg) const {
    Eigen::Vector3f c;
    for (std::size_t ch = 0; ch < 3; ++ch)
      c[Eigen::Index(ch)] = curves_[ch].at(shared_x_ ? seg : curves_[ch].locate(v));
    return c;
  }

 private:
  bool linear_;
  bool shared_x_ = false;  // the four curves have the same control x (one segment search per sample)
  std::array<FloatCurve, 4> curves_;
  std::vector<double> lo_, hi_, alpha_;
  std::vector<char> lo_closed_, hi_closed_;
  std::vector<Eigen::Vector3f> rgb01_;
};

/// The piecewise-linear kind on the lanes (the packets): FloatCurve's arithmetic per lane, bit for
/// bit. A lane's segment i (between control points i and i + 1) is the number of interior control
/// points x_j with v >= x_j: the segment the scalar forward scan stops at (the rounded x do not
/// decrease). Up to kLanes segments per curve are read with one permute (__builtin_shuffle), more
/// lane by lane.
class LaneLinearTf {
 public:
  using VF = packet::VF;
  using VI = packet::VI;
  explicit LaneLinearTf(const InlineTf& tf) : shared_(tf.shared_x()) {
    for (std::size_t c = 0; c < 4; ++c) curves_[c] = Curve(tf.curves()[c]);
  }
  /// Where v falls on a curve (for the shared points: any curve).
  struct Seg {
    VI front, back, idx;
    VF t;
  };
  /// α (curve 3) of v, each lane as InlineTf::alpha computes it, and where v fell on curve 3.
  [[gnu::always_inline]] VF alpha(VF v, Seg& seg) const {
    seg = curves_[3].locate(v);
    return curves_[3].at(seg);
  }
  /// The colour of v, each lane as InlineTf::rgb computes it (`seg` from alpha()).
  [[gnu::always_inline]] void rgb(VF v, const Seg& seg, VF& r, VF& g, VF& b) const {
    if (shared_) {
      r = curves_[0].at(seg), g = curves_[1].at(seg), b = curves_[2].at(seg);
    } else {
      r = curves_[0].at(curves_[0].locate(v)), g = curves_[1].at(curves_[1].locate(v));
      b = curves_[2].at(curves_[2].locate(v));
    }
  }

 private:
  class Curve {
   public:
    Curve() = default;
    explicit Curve(const FloatCurve& c) : c_(c) {
      small_ = c_.ax.size() <= std::size_t(packet::kLanes);
      if (small_)
        for (std::size_t i = 0; i < c_.ax.size(); ++i)
          tax_[i] = c_.ax[i], tdx_[i] = c_.dx[i], tay_[i] = c_.ay[i], tdy_[i] = c_.dy[i];
    }
    [[gnu::always_inline]] Seg locate(VF v) const {
      Seg s;
      s.front = ~VI(v > c_.x_front);  // !(v > x_0), NaN included
      s.back = VI(v >= c_.x_back);
      s.idx = VI{};
      for (float x : c_.interior) s.idx -= VI(v >= x);
      s.t = c_.n > 1 ? (v - read(tax_, c_.ax, s.idx)) / read(tdx_, c_.dx, s.idx) : packet::splatf(0);
      return s;
    }
    [[gnu::always_inline]] VF at(const Seg& s) const {
      if (c_.n == 0) return packet::splatf(0);
      if (c_.n == 1) return packet::splatf(c_.y_front);
      const VF mid = read(tay_, c_.ay, s.idx) + s.t * read(tdy_, c_.dy, s.idx);
      return packet::select(s.front, packet::splatf(c_.y_front),
                            packet::select(s.back, packet::splatf(c_.y_back), mid));
    }

   private:
    [[gnu::always_inline]] VF read(const VF& table, const std::vector<float>& values, VI idx) const {
      if (small_) return __builtin_shuffle(table, idx);
      VF r;
      for (int l = 0; l < packet::kLanes; ++l) r[l] = values[std::size_t(idx[l])];
      return r;
    }
    FloatCurve c_;
    bool small_ = true;
    VF tax_{}, tdx_{}, tay_{}, tdy_{};
  };
  bool shared_ = false;
  std::array<Curve, 4> curves_;
};

/// Where SlicingRenderer::live_sums_ keeps the number of live cells in [0, x) x [0, y) x [0, z): a
/// (cells + 1)-sided table, x fastest.
inline std::size_t live_sum_index(const std::array<int, 3>& cells, int x, int y, int z) {
  return std::size_t(x) + std::size_t(cells[0] + 1) * (std::size_t(y) + std::size_t(cells[1] + 1) * std::size_t(z));
}

/// The planes that may hold a fetched sample of one tile of pixels (SlicingRenderer's packets, with
/// empty-space skipping and a pinhole without distortion, whose pixels' rays are an affine family
/// of directions): plane k may where the box of the tile's samples on it — that of the four corner
/// rays' points, padded by 1e-3 voxel against the rounding of both — touches a live cell, its
/// voxels clamped as the samples' are. Computed 64 planes at a time when a walk first asks, so that
/// planes no ray of the tile meets (the box's ends, background tiles) cost nothing.
class TilePlanes {
 public:
  /// Corner c's point on plane k in index coordinates: base[c] + depth(k) along[c].
  std::array<Eigen::Vector3d, 4> base, along;
  const SliceStack* stack = nullptr;
  /// SlicingRenderer::live_sums_ (live_sum_index) over `cells`.
  const std::int32_t* live_sums = nullptr;
  std::array<int, 3> cells{}, dims{};
  int cell_shift = 2;
  std::int64_t tests = 0;  ///< planes tested

  void reset(int count) {
    words_.assign(std::size_t((count + 63) / 64), 0);
    ready_.assign(words_.size(), 0);
    count_ = count;
  }
  /// All planes (no bound: a corner ray that looks away from the planes).
  void all() {
    std::fill(words_.begin(), words_.end(), ~std::uint64_t(0));
    std::fill(ready_.begin(), ready_.end(), 1);
  }
  std::uint64_t word(int w) {
    if (ready_[std::size_t(w)] == 0) compute(w);
    return words_[std::size_t(w)];
  }

 private:
  void compute(int w) {
    std::uint64_t bits = 0;
    for (int k = 64 * w; k < std::min(64 * w + 64, count_); ++k) {
      const double d = stack->depth(k);
      int lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        double mn = std::numeric_limits<double>::infinity(), mx = -mn;
        for (int c = 0; c < 4; ++c) {
          const double x = base[std::size_t(c)][a] + d * along[std::size_t(c)][a];
          mn = std::min(mn, x), mx = std::max(mx, x);
        }
        const double top = double(dims[std::size_t(a)] - 1);
        lo[a] = int(std::clamp(std::floor(mn - 1e-3), 0.0, top)) >> cell_shift;
        hi[a] = int(std::clamp(std::floor(mx + 1e-3), 0.0, top)) >> cell_shift;
      }
      // The live cells in the box [lo, hi] from the prefix sums (inclusion-exclusion, no branch).
      auto at = [&](int x, int y, int z) { return live_sums[live_sum_index(cells, x, y, z)]; };
      const int x0 = lo[0], y0 = lo[1], z0 = lo[2], x1 = hi[0] + 1, y1 = hi[1] + 1, z1 = hi[2] + 1;
      const std::int32_t live = (at(x1, y1, z1) - at(x0, y1, z1) - at(x1, y0, z1) + at(x0, y0, z1)) -
                                (at(x1, y1, z0) - at(x0, y1, z0) - at(x1, y0, z0) + at(x0, y0, z0));
      bits |= std::uint64_t(live != 0) << (k & 63);
      ++tests;
    }
    words_[std::size_t(w)] = bits;
    ready_[std::size_t(w)] = 1;
  }
  std::vector<std::uint64_t> words_;
  std::vector<std::uint8_t> ready_;
  int count_ = 0;
};

/// What the packets' walk reads: the fetch bits and the tile's planes.
struct WalkGrid {
  const std::uint64_t* fetch_bits = nullptr;  ///< null: no empty-space skipping (every sample fetched)
  std::array<int, 3> dims{};
  int bricks_x = 0, bricks_y = 0;
  TilePlanes* planes = nullptr;  ///< null: every plane
};

/// One packet's lanes as the walk keeps them (packet::kLanes rays of a pixel block).
struct WalkLanes {
  packet::VU g[3];         ///< positions at plane `u` (32.32 fixed point, fixed_position.h)
  packet::VU dg[3];        ///< moves per plane
  packet::VI u0, uend;     ///< each lane's planes [u0, uend)
  packet::VI alive, done;  ///< lanes with planes; lanes stopped by early termination
  packet::VI visited;
  int u = 0, u_last = 0;  ///< the next plane to walk, the packet's last plane
};

/// The first plane u' >= u (in the walk's order) that the tile's planes may hold samples on, or
/// u_last + 1; `rest` gets the planes after u' in its word of 64 that the tile's planes may hold
/// samples on (bit j: plane k = 64 w + j), and `word_index` that word's index w. Without tile planes
/// every plane may. kFrontToBack: u = -k (else u = k).
template <bool kFrontToBack>
inline int next_plane(const WalkGrid& grid, int u, int u_last, std::uint64_t& rest, int& word_index) {
  if (u > u_last) return u;
  const bool all = grid.planes == nullptr;
  if constexpr (!kFrontToBack) {  // k = u rising
    int w = u >> 6;
    std::uint64_t word = (all ? ~std::uint64_t(0) : grid.planes->word(w)) & (~std::uint64_t(0) << (u & 63));
    while (word == 0) {
      if (++w > (u_last >> 6)) return u_last + 1;
      word = grid.planes->word(w);
    }
    rest = word & (word - 1), word_index = w;
    return std::min(64 * w + __builtin_ctzll(word), u_last + 1);
  }
  const int k = -u, k_last = -u_last;  // k falling to k_last
  int w = k >> 6;
  std::uint64_t word = (all ? ~std::uint64_t(0) : grid.planes->word(w)) & (~std::uint64_t(0) >> (63 - (k & 63)));
  while (word == 0) {
    if (--w < (k_last >> 6)) return u_last + 1;
    word = grid.planes->word(w);
  }
  const int top = 63 - __builtin_clzll(word);
  rest = word & ~(std::uint64_t(1) << top), word_index = w;
  return std::min(-(64 * w + top), u_last + 1);
}

/// The next plane of `rest` (next_plane's) in the walk's order, taken out of it.
template <bool kFrontToBack>
inline int pop_plane(std::uint64_t& rest, int word_index) {
  if constexpr (!kFrontToBack) {
    const int j = __builtin_ctzll(rest);
    rest &= rest - 1;
    return 64 * word_index + j;
  }
  const int top = 63 - __builtin_clzll(rest);
  rest &= ~(std::uint64_t(1) << top);
  return -(64 * word_index + top);
}

/// The walk of a packet (phase A of SlicingRenderer's packets): from plane w.u on, over the planes
/// the tile may hold samples on, each plane's lane positions and fetch bits (one gather of the bricks'
/// words); the planes where some lane fetches are queued with the lanes' mask (bit l: lane l), until
/// `max` are queued or the lanes' planes end (then w.u > w.u_last). Returns the number queued;
/// `visited` counts the walk per lane; front to back, `snapshots` gets each queued plane's counter after it (early
/// termination keeps a lane's count up to its last plane). Not inlined: the walk keeps its state in
/// registers apart from the fetch phase's.
template <bool kFrontToBack>
[[gnu::noinline]] int walk_planes(const WalkGrid& grid, WalkLanes& w, int max, int* queue_u, unsigned* queue_lanes,
                                  packet::VI* snapshots) {
  using namespace packet;
  const VI zero = splati(0);
  const VI dmax[3] = {splati(grid.dims[0] - 1), splati(grid.dims[1] - 1), splati(grid.dims[2] - 1)};
  const std::uint64_t* const bits_data = grid.fetch_bits;
  const int bx = grid.bricks_x, by = grid.bricks_y;
  VU g[3] = {w.g[0], w.g[1], w.g[2]};
  const VU dg[3] = {w.dg[0], w.dg[1], w.dg[2]};
  const VI u0 = w.u0, uend = w.uend, live = w.alive & ~w.done;
  VI visited = w.visited;
  int u = w.u;
  const int u_last = w.u_last;
  int queued = 0;
  // The planes come from a word of the tile's planes in a register (next_plane, then pop_plane):
  // the walk's next plane waits on no load.
  std::uint64_t rest = 0;
  int word_index = 0;
  while (queued < max) {
    const int next = rest != 0 ? pop_plane<kFrontToBack>(rest, word_index)
                               : next_plane<kFrontToBack>(grid, u, u_last, rest, word_index);
    if (next > u_last) {
      u = u_last + 1;
      break;
    }
    if (next != u) {  // a gap in the tile's planes (the planes of a run follow one another)
      const std::uint64_t move = std::uint64_t(std::int64_t(next - u));
      for (int a = 0; a < 3; ++a) g[a] += move * dg[a];
      u = next;
    }
    const VI inr = (u0 <= u) & (uend > u) & live;
    visited -= inr;
    VI sample = inr;
    if (bits_data != nullptr) {
      const VI ic[3] = {clamp(fixed::floor_voxel(g[0]), dmax[0]), clamp(fixed::floor_voxel(g[1]), dmax[1]),
                        clamp(fixed::floor_voxel(g[2]), dmax[2])};
      const VI brick = (ic[0] >> 2) + bx * ((ic[1] >> 2) + by * (ic[2] >> 2));
      const VI half = gather_i32(reinterpret_cast<const std::int32_t*>(bits_data),
                                 select(inr, 2 * brick + ((ic[2] >> 1) & 1), zero));
      sample &= ((half >> ((ic[0] & 3) | ((ic[1] & 3) << 2) | ((ic[2] & 1) << 4))) & 1) != 0;
    }
    const unsigned lanes = bits(sample);
    queue_u[queued] = u;
    queue_lanes[queued] = lanes;
    if constexpr (kFrontToBack) snapshots[queued] = visited;
    queued += lanes != 0 ? 1 : 0;
    ++u;
    for (int a = 0; a < 3; ++a) g[a] += dg[a];
  }
  for (int a = 0; a < 3; ++a) w.g[a] = g[a];
  w.visited = visited;
  w.u = u;
  return queued;
}

}  // namespace

std::string slicing_mode_name(SlicingMode m) {
  return m == SlicingMode::kBlend ? "blend" : m == SlicingMode::kMip ? "mip" : "combined";
}

bool slicing_needs_gradients(const SlicingSettings& s) { return s.mode != SlicingMode::kBlend || s.lit_blend; }

void check_slicing_settings(const Volume& volume, const SlicingSettings& s) {
  auto bad = [](const std::string& m) { throw InputError("slicing: " + m); };
  if (volume.empty()) bad("no volume");
  if (!(s.quality_class >= 0.01 && s.quality_class <= 1000))
    bad(fmt::format("quality_class must be in [0.01, 1000] (the source's [0.1, inf); got {})", s.quality_class));
  if (s.tile < 1 || s.tile > 4096) bad(fmt::format("tile must be in [1, 4096] (got {})", s.tile));
  if (s.value_range && !(s.value_range->second > s.value_range->first)) bad("the value range needs hi > lo");
  const BlinnPhong& L = s.light;
  if (!(L.ambient >= 0 && L.diffuse >= 0 && L.specular >= 0 && L.exponent >= 0 && L.gate >= 0 &&
        std::isfinite(L.ambient + L.diffuse + L.specular + L.exponent + L.gate) && L.light_camera.allFinite()))
    bad("the light's ambient, diffuse, specular, exponent and gate must be finite and >= 0");
  if (slicing_needs_gradients(s) && (s.gradient.radius < 1 || s.gradient.radius > 4))
    bad(fmt::format("gradient radius must be in [1, 4] (got {})", s.gradient.radius));
  if (slicing_needs_gradients(s) && s.gradient.bits != 4 && s.gradient.bits != 8)
    bad(fmt::format("gradient bits must be 8 or 4 (got {})", s.gradient.bits));
  if (!s.background.allFinite()) bad("the background must be finite");
  const auto d = volume.dims();
  if (std::max({d[0], d[1], d[2]}) >= (1 << 30))
    bad(fmt::format("a volume axis of 2^30 voxels or more is not supported (got {} x {} x {})", d[0], d[1], d[2]));
  if (s.skip_cell != 2 && s.skip_cell != 4 && s.skip_cell != 8 && s.skip_cell != 16)
    bad(fmt::format("skip_cell must be 2, 4, 8 or 16 voxels (got {})", s.skip_cell));
  if (!(s.early_termination >= 0 && s.early_termination <= 1))
    bad(fmt::format("early_termination must be in [0, 1] (0: off; got {})", s.early_termination));
}

SlicingRenderer::SlicingRenderer(const Volume& volume, const SlicingSettings& settings,
                                 std::optional<GradientVolume> gradients)
    : volume_(volume), s_(settings), grad_(std::move(gradients)) {
  check_slicing_settings(volume, settings);
  if (s_.value_range) {
    lo_ = s_.value_range->first, hi_ = s_.value_range->second;
  } else {
    const auto r = volume.value_range();
    lo_ = r[0], hi_ = r[1] > r[0] ? r[1] : r[0] + 1;  // a constant volume maps to 0
  }
  if (slicing_needs_gradients(s_)) {
    if (!grad_) grad_ = build_gradient_volume(volume, s_.gradient);
    if (grad_->dims != volume.dims())
      throw InputError("slicing: the gradient volume does not match the data volume's dimensions");
    // The packets' lighting reads a voxel's three channels by one 32-bit gather (voxel indices fit).
    const std::int64_t voxels = std::int64_t(grad_->dims[0]) * grad_->dims[1] * grad_->dims[2];
    if (s_.simd && voxels < (std::int64_t(1) << 31)) {
      grad_words_.resize(std::size_t(voxels));
      const std::uint8_t* e = grad_->encoded.data();
      tbb::parallel_for(std::int64_t(0), voxels, [&](std::int64_t v) {
        const std::size_t o = 3 * std::size_t(v);
        grad_words_[std::size_t(v)] = std::int32_t(e[o]) | std::int32_t(e[o + 1]) << 8 | std::int32_t(e[o + 2]) << 16;
      });
    }
  } else {
    grad_.reset();
  }
  if (!s_.mask.empty()) {
    const auto h = s_.mask.histogram();
    for (int i = 0; i < 4; ++i) tf_used_[std::size_t(i)] = h[std::size_t(i) + 1] > 0;
  }
  if (s_.skip_empty) {
    const int kCellShift = cell_shift_ = s_.skip_cell == 2 ? 1 : s_.skip_cell == 4 ? 2 : s_.skip_cell == 8 ? 3 : 4;
    for (int a = 0; a < 3; ++a) cells_[std::size_t(a)] = ((volume.dims()[std::size_t(a)] - 1) >> kCellShift) + 1;
    const std::size_t n_cells = std::size_t(cells_[0]) * cells_[1] * cells_[2];
    auto cell_of = [&](int ci, int cj, int ck) {
      return std::size_t(ci) + std::size_t(cells_[0]) * (std::size_t(cj) + std::size_t(cells_[1]) * std::size_t(ck));
    };
    const std::array<bool, 4>& used = tf_used_;
    const double inv = 1.0 / (hi_ - lo_);
    // Whether a TF in use can see some value in [mn, mx] (voxel values, padded by 1e-5 of their
    // magnitude for the float round-off of a trilinear fetch): the test of the cells and of the
    // voxel bits.
    auto any_tf_sees = [&](double mn, double mx) {
      const double pad = 1e-5 * std::max({std::abs(mn), std::abs(mx), 1.0});
      const double a = (mn - pad - lo_) * inv, b = (mx + pad - lo_) * inv;
      for (int t = 0; t < 4; ++t)
        if (used[std::size_t(t)] && s_.tfs[std::size_t(t)].visible_in(a, b)) return true;
      return false;
    };
    // The cells whose values (each cell's voxels [e c, e c + e], e the cell edge; the + e is the
    // trilinear neighbour) a TF in use can see.
    std::vector<std::uint8_t> range_live(n_cells, 0);
    visit_samples(volume, [&](const auto v) {
      tbb::parallel_for(0, cells_[2], [&](int ck) {
        for (int cj = 0; cj < cells_[1]; ++cj)
          for (int ci = 0; ci < cells_[0]; ++ci) {
            double mn = 1e300, mx = -1e300;
            for (int k = ck << kCellShift; k <= std::min((ck + 1) << kCellShift, v.nz - 1); ++k)
              for (int j = cj << kCellShift; j <= std::min((cj + 1) << kCellShift, v.ny - 1); ++j)
                for (int i = ci << kCellShift; i <= std::min((ci + 1) << kCellShift, v.nx - 1); ++i) {
                  const double x = double(v.at(i, j, k));
                  mn = std::min(mn, x);
                  mx = std::max(mx, x);
                }
            range_live[cell_of(ci, cj, ck)] = any_tf_sees(mn, mx);
          }
      });
    });
    // The fetch bits (SlicingSettings::skip_voxels), brick by brick in parallel: with the voxel
    // bits, a voxel of a live cell whose stencil {i, i + 1} x {j, j + 1} x {k, k + 1} (clamped as
    // the fetch clamps) holds a value a TF in use can see; without them, every voxel of a live cell.
    const std::array<int, 3> nd = volume.dims();
    for (int a = 0; a < 3; ++a) bricks_[std::size_t(a)] = (nd[std::size_t(a)] + 3) >> 2;
    fetch_bits_.assign(std::size_t(bricks_[0]) * bricks_[1] * bricks_[2], 0);
    visit_samples(volume, [&](const auto v) {
      tbb::parallel_for(0, bricks_[2], [&](int bk) {
        for (int bj = 0; bj < bricks_[1]; ++bj)
          for (int bi = 0; bi < bricks_[0]; ++bi) {
            std::uint64_t word = 0;
            for (int k = 4 * bk; k < std::min(4 * bk + 4, nd[2]); ++k)
              for (int j = 4 * bj; j < std::min(4 * bj + 4, nd[1]); ++j)
                for (int i = 4 * bi; i < std::min(4 * bi + 4, nd[0]); ++i) {
                  if (range_live[cell_of(i >> kCellShift, j >> kCellShift, k >> kCellShift)] == 0) continue;
                  bool fetch = true;
                  if (s_.skip_voxels) {
                    const int i1 = std::min(i + 1, nd[0] - 1), j1 = std::min(j + 1, nd[1] - 1),
                              k1 = std::min(k + 1, nd[2] - 1);
                    double mn = 1e300, mx = -1e300;
                    for (const int kk : {k, k1})
                      for (const int jj : {j, j1})
                        for (const int ii : {i, i1}) {
                          const double x = double(v.at(ii, jj, kk));
                          mn = std::min(mn, x);
                          mx = std::max(mx, x);
                        }
                    fetch = any_tf_sees(mn, mx);
                  }
                  if (fetch) word |= std::uint64_t(1) << fetch_bit(i, j, k);
                }
            fetch_bits_[std::size_t(bi) + std::size_t(bricks_[0]) * (std::size_t(bj) + std::size_t(bricks_[1]) * bk)] =
                word;
          }
      });
    });
    // A cell is live where some sample in it is fetched: some voxel of it has its fetch bit (a
    // cell of 4³ voxels is a brick; 8³ and 16³ cells hold whole bricks; 2³ cells are octants of one).
    live_.assign(n_cells, 0);
    for (int bk = 0; bk < bricks_[2]; ++bk)
      for (int bj = 0; bj < bricks_[1]; ++bj)
        for (int bi = 0; bi < bricks_[0]; ++bi) {
          const std::uint64_t word =
              fetch_bits_[std::size_t(bi) + std::size_t(bricks_[0]) * (std::size_t(bj) + std::size_t(bricks_[1]) * bk)];
          if (word == 0) continue;
          if (kCellShift >= 2) {
            live_[cell_of(bi >> (kCellShift - 2), bj >> (kCellShift - 2), bk >> (kCellShift - 2))] = 1;
            continue;
          }
          for (int o = 0; o < 8; ++o) {  // the octant (ox, oy, oz) of the brick: voxels 2 o.. 2 o + 1
            const int ox = o & 1, oy = (o >> 1) & 1, oz = o >> 2;
            std::uint64_t octant = 0;
            for (int dz = 0; dz < 2; ++dz)
              for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx)
                  octant |= std::uint64_t(1) << fetch_bit(2 * ox + dx, 2 * oy + dy, 2 * oz + dz);
            const int ci = 2 * bi + ox, cj = 2 * bj + oy, ck = 2 * bk + oz;
            if ((word & octant) != 0 && ci < cells_[0] && cj < cells_[1] && ck < cells_[2])
              live_[cell_of(ci, cj, ck)] = 1;
          }
        }
    // Chebyshev distance to the nearest cell of a set: breadth-first search from every cell of it
    // over the 26 neighbours (exact for the chessboard metric), capped at 255.
    const int cx = cells_[0], cy = cells_[1], cz = cells_[2];
    auto chebyshev = [&](bool to_live) {
      std::vector<std::uint8_t> dist(live_.size(), 255);
      std::vector<int> queue;
      for (std::size_t i = 0; i < live_.size(); ++i)
        if ((live_[i] != 0) == to_live) dist[i] = 0, queue.push_back(int(i));
      for (std::size_t head = 0; head < queue.size(); ++head) {
        const int c = queue[head];
        const int d = dist[std::size_t(c)] + 1;
        if (d > 255) continue;
        const int ci = c % cx, cj = (c / cx) % cy, ck = c / (cx * cy);
        for (int dk = -1; dk <= 1; ++dk)
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int i = ci + di, j = cj + dj, k = ck + dk;
              if (i < 0 || j < 0 || k < 0 || i >= cx || j >= cy || k >= cz) continue;
              const std::size_t n = cell_of(i, j, k);
              if (dist[n] > d) dist[n] = std::uint8_t(d), queue.push_back(int(n));
            }
      }
      return dist;
    };
    dist_ = chebyshev(true);
    // For live cells, the radius of the cube of cells around them that are all live: the distance
    // to the nearest empty cell minus one (254 where none is within the cap).
    live_reach_ = chebyshev(false);
    for (auto& r : live_reach_) r = std::uint8_t(r == 0 ? 0 : r - 1);
    // Prefix sums of the live cells (the packets' tile planes count the live cells of a box by
    // eight of them).
    live_sums_.assign(live_sum_index(cells_, 0, 0, cz + 1), 0);
    auto at = [&](int x, int y, int z) -> std::int32_t& { return live_sums_[live_sum_index(cells_, x, y, z)]; };
    for (int k = 1; k <= cz; ++k)
      for (int j = 1; j <= cy; ++j)
        for (int i = 1; i <= cx; ++i) {
          at(i, j, k) = std::int32_t(live_[cell_of(i - 1, j - 1, k - 1)]) + at(i - 1, j, k) + at(i, j - 1, k) +
                        at(i, j, k - 1) - at(i - 1, j - 1, k) - at(i - 1, j, k - 1) - at(i, j - 1, k - 1) +
                        at(i - 1, j - 1, k - 1);
        }
  }
}

SlicingFrame SlicingRenderer::render(const Camera& camera) const {
  SlicingFrame frame;
  render_into(camera, frame);
  return frame;
}

void SlicingRenderer::render_into(const Camera& camera, SlicingFrame& frame) const {
  const auto* pin = std::get_if<Pinhole>(&camera);
  if (!pin) throw InputError("slicing: the slicing renderer needs a pinhole camera");
  const RayGenerator rays(camera);
  const Box3 box = volume_.domain();
  const Eigen::Isometry3d world_from_camera = pin->camera_from_world.inverse();
  const Eigen::Vector3d eye = world_from_camera.translation();
  if (box.contains(eye)) throw InputError("slicing: the eye is inside the volume's box");
  const double h0 = volume_.spacing().minCoeff();
  const SliceStack stack = slice_stack(box, eye, slice_spacing(s_.quality_class, volume_.spacing()), s_.d_range);
  const Eigen::Vector3d light_pos = eye + world_from_camera.linear() * (s_.light.light_camera * box.diagonal());
  const int W = pin->width, H = pin->height;
  // Every pixel of raw and alpha is written below, so images of the right size are reused as
  // they are.
  frame.raw.reshape(W, H, 3);
  frame.alpha.reshape(W, H, 1);
  // A post chain that only clamps (no bloom, the identity adjustment: the scenes' default) is
  // applied as each pixel is written, instead of by a second pass over the frame.
  check_bloom_settings(s_.post);
  const bool post_clamp = bloom_is_clamp(s_.post);
  if (post_clamp) frame.rgb.reshape(W, H, 3);
  auto write_pixel = [&frame, post_clamp](int x, int y, const Eigen::Vector3d& out, double alpha) {
    for (int ch = 0; ch < 3; ++ch) {
      const float v = float(out[ch]);
      frame.raw.at(x, y, ch) = v;
      if (post_clamp) frame.rgb.at(x, y, ch) = ColorAdjust::identity_value(v);
    }
    frame.alpha.at(x, y) = float(alpha);
  };
  frame.stats = SlicingStats{};
  frame.stats.slices = stack.count;
  frame.stats.slice_spacing = stack.spacing;
  const bool lit = slicing_needs_gradients(s_);
  const bool use_mask = !s_.mask.empty();
  const bool skip = !live_.empty();
  const int cell_shift = cell_shift_;
  const std::size_t cells_x = std::size_t(cells_[0]), cells_y = std::size_t(cells_[1]);
  const std::uint8_t* const dist_cells = dist_.data();  // the distance map answers "live" too (0)
  const std::uint8_t* const live_reach = live_reach_.data();
  const std::array<int, 3> dims = volume_.dims();
  const double inv_range = 1.0 / (hi_ - lo_);
  // The linear kind's sample value in float: (f - lo) / (hi - lo) with both rounded to float.
  const float lo_f = float(lo_), inv_range_f = float(inv_range);
  const Eigen::Vector3d origin = volume_.origin(), inv_spacing = volume_.spacing().cwiseInverse();
  std::array<VolumeSamples<std::uint8_t>, 3> gch;
  double grad_scale = 0;
  if (lit) {
    for (int c = 0; c < 3; ++c) gch[std::size_t(c)] = grad_->channel(c);
    grad_scale = 1;
  }
  std::vector<InlineTf> tfs;
  for (const auto& tf : s_.tfs) tfs.emplace_back(tf);
  const bool front_to_back =
      s_.early_termination > 0 && s_.mode == SlicingMode::kBlend && s_.blend == BlendOperator::kOver;
  const float stop_alpha = float(s_.early_termination);  // compared with the float A
  const int T = s_.tile;
  const int tiles_x = (W + T - 1) / T, tiles_y = (H + T - 1) / T;
  std::vector<TileCounts> counts(std::size_t(tiles_x) * tiles_y);
  const auto t0 = std::chrono::steady_clock::now();
  const SlicingMode mode = s_.mode;
  const BlendOperator blend_op = s_.blend;
  const BlinnPhong light = s_.light;
  const Eigen::Vector3d background = s_.background;
  const bool exact_positions = s_.exact_positions;
  const bool live_runs = s_.live_runs;
  int max_pieces = 1;
  for (const auto& tf : tfs) max_pieces = std::max(max_pieces, tf.pieces());
  // The packets' TF on eight lanes: the constant kind's range tests, the linear kind's segments.
  std::array<std::optional<LaneLinearTf>, 4> lane_tfs;
  for (std::size_t t = 0; t < 4; ++t)
    if (tfs[t].linear()) lane_tfs[t].emplace(tfs[t]);
  // The fetch bits in bricks of 4³ voxels (null without empty-space skipping).
  const std::uint64_t* const fetch_bits = fetch_bits_.empty() ? nullptr : fetch_bits_.data();
  const int bricks_x = bricks_[0], bricks_y = bricks_[1];
  auto fetch_bit_set = [&](int i, int j, int k) {
    const std::size_t b =
        std::size_t(i >> 2) + std::size_t(bricks_x) * (std::size_t(j >> 2) + std::size_t(bricks_y) * (k >> 2));
    return ((fetch_bits[b] >> fetch_bit(i, j, k)) & 1) != 0;
  };
  // The packets' walk (walk_planes).
  WalkGrid grid;
  grid.fetch_bits = fetch_bits, grid.dims = dims, grid.bricks_x = bricks_x, grid.bricks_y = bricks_y;
  // The tiles' planes: the corner rays bound a tile's samples on a plane where the pixels' rays are
  // an affine family of directions (a pinhole without distortion).
  const bool tile_bounds = !pin->distorted();
  // The planes are bounded per block of pixels whose samples on a plane spread over about two cells
  // (at the box's centre): a tile of a fine image, fewer pixels where there are few pixels per voxel
  // (a block's box would cover most of a small volume), down to one packet.
  const double voxels_per_pixel = (box.centre() - eye).dot(stack.n) / pin->fy / h0;
  const int block_px = int(std::min(double(s_.tile), double(2 << cell_shift_) / std::max(voxels_per_pixel, 1e-9)));
  const int block_x = std::max(packet::kLanesX, block_px / packet::kLanesX * packet::kLanesX);
  const int block_y = std::max(2, block_px / 2 * 2);
  // Every ray's set-up (ray_setup.h): an undistorted pinhole's directions from its parameters, a
  // distorted one's from RayGenerator.
  const bool pinhole_rays = !pin->distorted();
  ray_setup::Frame ray_frame = ray_setup::plane_frame(stack, box, eye);
  ray_frame.cx = pin->cx, ray_frame.cy = pin->cy, ray_frame.fx = pin->fx, ray_frame.fy = pin->fy;
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) ray_frame.rot[a][b] = world_from_camera.linear()(a, b);
    ray_frame.origin[a] = origin[a], ray_frame.inv_spacing[a] = inv_spacing[a];
  }
  ray_frame.h0 = h0, ray_frame.opacity_correction = s_.opacity_correction;
  ray_frame.sign = front_to_back ? 1.0 : -1.0;
  // The gradient for the packets' lighting: the three encoded channels of a voxel in one word.
  const std::int32_t* const grad_words = grad_words_.empty() ? nullptr : grad_words_.data();
  const float grad_channel_scale = lit ? grad_->channel(0).scale : 1.0f;
  // The mask in the samples' index coordinates (MaskIndexLookup: the same bits per ray and on the lanes).
  const MaskIndexLookup mask_index = use_mask ? s_.mask.index_lookup(origin, volume_.spacing()) : MaskIndexLookup{};
  // Packets index the samples with 32-bit element offsets (and read 32-bit cell records).
  const auto st = volume_.strides();
  const bool offsets_fit =
      st[0] >= 0 && st[1] >= 0 && st[2] >= 0 &&
      (dims[0] - 1) * st[0] + (dims[1] - 1) * st[1] + (dims[2] - 1) * st[2] < (std::int64_t(1) << 31);
  const bool x_packed = st[0] == 1;  // neighbouring x samples adjacent (the packets' paired fetch)
  const bool use_packets = s_.simd && !exact_positions && offsets_fit;  // packets: incremental positions
  // The corrected α 1 - (1 - a)^e (per sample of the linear kind, per ray and piece of the constant
  // kind): lane_math::corrected_alpha, whose lanes give its scalar bits (SlicingSettings::exact_pow:
  // std::pow).
  const bool exact_pow = s_.exact_pow;
  auto correct = [exact_pow](double a, double e) {
    return exact_pow ? 1.0 - std::pow(1.0 - a, e) : lane_math::corrected_alpha(a, e);
  };
  // The linear kind's, in float (corrected_alpha_f; exact_pow: std::pow in double, rounded).
  auto correct_f = [exact_pow](float a, float e) {
    return exact_pow ? float(1.0 - std::pow(1.0 - double(a), double(e))) : lane_math::corrected_alpha_f(a, e);
  };
  // The specular power (the same choice; an integer exponent by lane_math::int_pow).
  const int int_exponent = lane_math::int_exponent(light.exponent);
  auto power = [exact_pow, int_exponent](double x, double y) {
    return exact_pow ? std::pow(x, y) : lane_math::specular_power(x, int_exponent, y);
  };
  // The lighting's constants in float, and its sums of three products in the one order both paths
  // use, (x + y) + z (Eigen's float reductions of a Vector3f add in another): x, y a Vector3f or the
  // lanes' three VF.
  auto dot3 = [](const auto& x, const auto& y) { return (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2]; };
  const Eigen::Vector3f light_pos_f = light_pos.cast<float>(), inv_spacing_f = inv_spacing.cast<float>();
  const float grad_scale_f = float(grad_scale), gate_f = float(light.gate);
  const float ambient_f = float(light.ambient), diffuse_f = float(light.diffuse), specular_f = float(light.specular);
  visit_samples(volume_, [&](const auto samples) {
    // Blinn-Phong of a lit sample: colour c at the stencil (i0, j0, k0) with weights w, world point
    // p, unit vector towards the eye.
    // In float, as the TF's colour it shades (issue 17's thirteenth round), but for the specular power
    // (power() in double, rounded).
    auto shade = [&](Eigen::Vector3f& c, int i0, int j0, int k0, float wx, float wy, float wz, const Eigen::Vector3f& p,
                     const Eigen::Vector3f& to_eye) {
      Eigen::Vector3f e;
      for (int ch = 0; ch < 3; ++ch) e[ch] = gch[std::size_t(ch)].trilinear_cell(i0, j0, k0, wx, wy, wz);
      auto normalized = [&](const Eigen::Vector3f& x) {
        const float z = dot3(x, x);
        return z > 0 ? Eigen::Vector3f(x / std::sqrt(z)) : x;
      };
      const Eigen::Vector3f gd = (2.0f * e - Eigen::Vector3f::Ones()) * grad_scale_f;
      const Eigen::Vector3f gw = gd.cwiseProduct(inv_spacing_f);  // index units -> world direction
      if (std::sqrt(dot3(gd, gd)) > gate_f && std::sqrt(dot3(gw, gw)) > 0) {
        const Eigen::Vector3f nrm = -normalized(gw);
        const Eigen::Vector3f l = normalized(light_pos_f - p);
        const Eigen::Vector3f h = normalized(l + to_eye);
        const float diff = std::max(dot3(nrm, l), 0.0f);
        const float spec = float(power(double(std::max(dot3(nrm, h), 0.0f)), light.exponent));
        c = c * (ambient_f + diffuse_f * diff) + Eigen::Vector3f::Constant(specular_f * spec);
      }
    };
    // One tile, specialised on what changes per frame only (lit, masked, front to back), so that
    // the sample loop carries no tests of settings.
    auto do_tile = [&](int tx, int ty, auto lit_c, auto masked_c, auto ftb_c) {
      constexpr bool kLit = decltype(lit_c)::value, kMasked = decltype(masked_c)::value;
      constexpr bool kFrontToBack = decltype(ftb_c)::value;
      // Unlit Blend composites invisible samples too (α = 0 leaves C and A bit for bit as they are:
      // 0 · c + 1 · C = C, 0 + 1 · A = A), so the loop has no branch on the noisy classification.
      const bool blend_all = !kLit && mode == SlicingMode::kBlend;
      TileCounts cnt;
      // Corrected α of each constant-kind piece, computed once per ray when first met (stamp: the
      // ray that computed it); std::pow with the same arguments as per sample: the same bits.
      std::vector<float> ac_piece(std::size_t(4 * max_pieces), 0.0f);
      std::vector<std::int64_t> ac_stamp(std::size_t(4 * max_pieces), -1);
      std::int64_t ray_id = 0;
      for (int y = ty * T; y < std::min(H, (ty + 1) * T); ++y)
        for (int x = tx * T; x < std::min(W, (tx + 1) * T); ++x) {
          // The ray and its planes (ray_setup.h: the packets' lanes compute the same bits).
          CameraRay ray;
          ray.origin = eye;
          double v[3];
          if (pinhole_rays) {
            ray_setup::pinhole_direction(ray_frame, double(x), double(y), v);
          } else {
            const Eigen::Vector3d d = rays.generate_ray(x, y).direction;
            v[0] = d.x(), v[1] = d.y(), v[2] = d.z();
          }
          ray.direction = Eigen::Vector3d(v[0], v[1], v[2]);
          const ray_setup::Rays<double> rr = ray_setup::rays_from(ray_frame, v);
          RaySlices rs;
          rs.k_first = rr.k_first, rs.k_last = rr.k_last, rs.t_offset = ray_frame.t_offset, rs.cos_psi = rr.cos_psi;
          SliceAccumulator acc;
          if (!rs.empty()) {
            ++cnt.rays;
            ++ray_id;
            const double exponent = rr.exponent;
            const float exponent_f = float(exponent);  // the linear kind's
            const Eigen::Vector3f to_eye_f = (-ray.direction).cast<float>();
            // The move of g (index units) from one visited plane to the next (t_k is linear in k and
            // falls with k: back to front walks towards the eye).
            const Eigen::Vector3d delta =
                (kFrontToBack ? 1.0 : -1.0) * (stack.spacing / rs.cos_psi) * ray.direction.cwiseProduct(inv_spacing);
            // The linear kind: the last α seen and its corrected value (std::pow only when α changes).
            float last_a = -1, last_ac = 0;
            const int n_samples = rs.k_last - rs.k_first + 1;
            std::int64_t n_visited = 0, n_skipped = 0, n_classified = 0, n_jumped = 0, n_cell_tests = 0;
            // The planes from the current sample on while g stays 0.01 index units inside the cube
            // of cells c ± r (c the current sample's cell, r in cells) along this ray, capped at
            // `run`: the cube is [e (c - r), e (c + r + 1)) per axis (e the cell edge; a side at the
            // volume's border reaches to infinity, where clamping keeps the index in the cube). The
            // 0.01 absorbs the float rounding of g (~1e-12 for |g| < 4096) and of the reciprocal of
            // dg. On an axis where g moves by more than 1e-6 per plane it moves monotonically, so
            // only the side ahead bounds the run; on an (almost) still axis, t_k's round-off could
            // move g either way across a side it sits on: no run unless 0.01 inside both sides.
            const Eigen::Vector3d inv_delta = delta.cwiseInverse();
            auto cube_run = [&](const int cc[3], int r, const Eigen::Vector3d& gs, double run) {
              for (int a = 0; a < 3; ++a) {
                const double d = delta[a];
                const bool open_hi = cc[a] + r >= cells_[std::size_t(a)] - 1, open_lo = cc[a] - r <= 0;
                const double hi = double((cc[a] + r + 1) << cell_shift), lo = double((cc[a] - r) << cell_shift);
                if (d > 1e-6) {
                  if (!open_hi) run = std::min(run, (hi - 0.01 - gs[a]) * inv_delta[a]);
                } else if (d < -1e-6) {
                  if (!open_lo) run = std::min(run, (lo + 0.01 - gs[a]) * inv_delta[a]);
                } else if ((!open_hi && gs[a] > hi - 0.01) || (!open_lo && gs[a] < lo + 0.01)) {
                  run = 0;
                }
              }
              return run;
            };
            int live_until = 0;  // steps before this one lie in a live run
            for (int step = 0; step < n_samples; ++step) {
              const int k = kFrontToBack ? rs.k_last - step : rs.k_first + step;
              ++n_visited;
              // g: the sample's index coordinates (i0, j0, k0 its stencil's lower corner, w the
              // weights); p (world) where the light needs it.
              Eigen::Vector3d g, p;
              int i0, j0, k0;
              float wx, wy, wz;
              if (exact_positions) {
                p = ray.origin + rs.t(stack, k) * ray.direction;
                g = (p - origin).cwiseProduct(inv_spacing);
                const float gx = float(g.x()), gy = float(g.y()), gz = float(g.z());
                const float fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
                i0 = int(fx), j0 = int(fy), k0 = int(fz);
                wx = gx - fx, wy = gy - fy, wz = gz - fz;
              } else {
                // The samples' positions g_0 + step Δg in fixed point (fixed_position.h).
                std::uint64_t q[3];
                for (int a = 0; a < 3; ++a) q[a] = rr.g0[a] + std::uint64_t(step) * rr.dg[a];
                i0 = fixed::floor_voxel(q[0]), j0 = fixed::floor_voxel(q[1]), k0 = fixed::floor_voxel(q[2]);
                wx = fixed::weight(q[0]), wy = fixed::weight(q[1]), wz = fixed::weight(q[2]);
                g = Eigen::Vector3d(fixed::to_double(q[0]), fixed::to_double(q[1]), fixed::to_double(q[2]));
                if constexpr (kLit) p = ray.origin + rs.t(stack, k) * ray.direction;
              }
              const int ic0 = std::clamp(i0, 0, dims[0] - 1), ic1 = std::clamp(j0, 0, dims[1] - 1),
                        ic2 = std::clamp(k0, 0, dims[2] - 1);
              if (skip && step >= live_until) {
                ++n_cell_tests;
                const int c0 = ic0 >> cell_shift, c1 = ic1 >> cell_shift, c2 = ic2 >> cell_shift;
                const std::size_t cell = std::size_t(c0) + cells_x * (std::size_t(c1) + cells_y * std::size_t(c2));
                const int dist = dist_cells[cell];  // 0: live
                const int cc[3] = {c0, c1, c2};
                if (dist != 0) {
                  ++n_skipped;
                  // Jump the run of empty planes: every cell within D - 1 of this one (max norm) is
                  // empty, D = dist_ the distance to the nearest live cell; the planes while g stays
                  // 0.01 index units inside that cube (cube_run) are empty and are counted as
                  // skipped without being visited.
                  const double run = cube_run(cc, dist - 1, g, double(n_samples - 1 - step));
                  if (run >= 1) {
                    const int n = int(run);
                    step += n;
                    n_jumped += n;
                  }
                  continue;
                }
                // A live run (the lead's "proximity clouds" in volume_integrator.cpp): every cell
                // within R of this one is live (R = live_reach_), so the planes while g stays 0.01
                // inside that cube are in live cells and are sampled without the cell test (the same
                // samples, classifications and counts as testing each).
                if (live_runs) {
                  const double run = cube_run(cc, live_reach[cell], g, double(n_samples - 1 - step));
                  live_until = step + 1 + (run >= 1 ? int(run) : 0);
                }
              }
              // The fetch bits: with the voxel bits, no TF in use can see this sample's stencil (α =
              // 0), so it is not fetched.
              if (skip && !fetch_bit_set(ic0, ic1, ic2)) {
                ++n_skipped;
                continue;
              }
              int m = 1;
              if constexpr (kMasked) {
                m = mask_index.lookup(i0, j0, k0, wx, wy, wz);
                if (m == 0) continue;
              }
              ++n_classified;
              const float f = samples.trilinear_cell(i0, j0, k0, wx, wy, wz);
              const std::size_t ti = std::size_t(m - 1);
              const InlineTf& tf = tfs[ti];
              int piece = 0;
              FloatCurve::Segment seg;
              float fn_f = 0;
              float a, ac;
              if (tf.linear()) {
                fn_f = (f - lo_f) * inv_range_f;
                const float af = tf.alpha(fn_f, seg);
                if (!(af > 0)) continue;
                float acf = af;
                if (exponent_f != 1.0f) {
                  if (af != last_a) last_a = af, last_ac = correct_f(af, exponent_f);
                  acf = last_ac;
                }
                a = af, ac = acf;
              } else {
                const double fn = (double(f) - lo_) * inv_range;
                piece = tf.piece(fn);
                a = float(tf.piece_alpha(piece));
                if (!blend_all && !(a > 0)) continue;
                ac = a;
                if (exponent != 1.0 && piece != 0) {
                  const std::size_t slot = ti * std::size_t(max_pieces) + std::size_t(piece);
                  if (ac_stamp[slot] != ray_id)
                    ac_stamp[slot] = ray_id, ac_piece[slot] = float(correct(tf.piece_alpha(piece), exponent));
                  ac = ac_piece[slot];
                }
              }
              Eigen::Vector3f c = tf.linear() ? tf.rgb(fn_f, seg) : tf.piece_rgb(piece);
              if constexpr (kLit) shade(c, i0, j0, k0, wx, wy, wz, p.cast<float>(), to_eye_f);
              if constexpr (kFrontToBack) {
                const float w = (1 - acc.A) * ac;
                acc.C += w * c;
                acc.A += w;
                if (acc.A >= stop_alpha) {
                  ++cnt.terminated;
                  break;
                }
                continue;
              }
              switch (mode) {
                case SlicingMode::kBlend:
                  if (blend_op == BlendOperator::kOver)
                    acc.blend_over(c, ac);
                  else
                    acc.blend_additive(c, ac);
                  break;
                case SlicingMode::kMip:
                  acc.mip(c, a);
                  break;
                case SlicingMode::kCombined:
                  acc.combined(c, a, ac);
                  break;
              }
            }
            cnt.samples += n_visited + n_jumped;
            cnt.visited += n_visited;
            cnt.skipped += n_skipped + n_jumped;
            cnt.classified += n_classified;
            cnt.cell_tests += n_cell_tests;
          }
          const Eigen::Vector3d C = acc.C.cast<double>();
          const double A = acc.A;
          const Eigen::Vector3d out =
              mode == SlicingMode::kBlend ? Eigen::Vector3d(C + (1 - A) * background) : (A > 0 ? C : background);
          write_pixel(x, y, out, A);
        }
      counts[std::size_t(ty) * tiles_x + tx] = cnt;
    };
    // The SIMD path (SlicingSettings::simd): packets of neighbouring pixels of a tile (4 x 2 on
    // eight lanes, 2 x 2 on four), each lane one ray with its scalar state (fixed-point first
    // position and move per plane, its planes [u0, u0 + ns)). The packet walks the planes U in
    // the scalar loop's order (u = k back to front, u = -k front to back) in two phases that take
    // turns over chunks of planes:
    //  A, the walk: every lane's position (integer adds), its brick word of fetch bits (one 64-bit
    //    gather) and so which lanes fetch at this plane; where no lane in range is in a brick with
    //    a fetch bit, the empty-space cells are looked up and, where every lane is in an empty
    //    cell, the packet jumps the planes while all stay in their empty cubes. Planes where some
    //    lane fetches are queued with the lanes' mask.
    //  B, the fetch: per queued plane, the lanes' positions again (g_0 + j Δg: the same integers),
    //    mask, trilinear corners, TF, light and compositing on the lanes, with no branch of the walk
    //    in between, so the gathers of one plane overlap the arithmetic of the last.
    // A lane fetches exactly the samples whose fetch bit is set, with its ray's arithmetic (the
    // scalar code's operations in its order), so the image and the samples, skipped, classified
    // and terminated counts are the scalar path's bit for bit; visited and cell_tests count the
    // packet's own walk. Early termination ends a lane in phase B; its planes already queued are
    // masked there, and the walk leaves it out from then on.
    auto do_packet_tile = [&](int tx, int ty, auto lit_c, auto masked_c, auto ftb_c) {
      using namespace packet;
      constexpr bool kLit = decltype(lit_c)::value, kMasked = decltype(masked_c)::value;
      constexpr bool kFrontToBack = decltype(ftb_c)::value;
      TileCounts cnt;
      // Corrected α per lane of each constant piece (slot t · max_pieces + piece), computed when a
      // lane first meets it (-1: not yet), as the scalar loop's per-ray table.
      std::vector<VF> acp(std::size_t(4 * max_pieces));
      const VI cell_max[3] = {splati(dims[0] - 1), splati(dims[1] - 1), splati(dims[2] - 1)};
      const VI str[3] = {splati(std::int32_t(samples.sx)), splati(std::int32_t(samples.sy)),
                         splati(std::int32_t(samples.sz))};
      const VI zero = splati(0), one = splati(1);
      const VI gstr[3] = {splati(1), splati(dims[0]), splati(dims[0] * dims[1])};  // grad_words_ (voxels)
      const VI lane_bit = lane_bits();
      // The queue of phase A: planes where some lane fetches, and which lanes.
      // Planes queued per walk: front to back fewer, since the walk runs ahead of a lane's
      // termination (the phantom's Blend at QC 1, early termination 0.99: 135-153 ms with 64, 98 ms
      // with 8; back to front 64, 16 and 8 within the noise).
      constexpr int kQueue = 64, kQueueFrontToBack = 8;
      std::array<int, kQueue> queue_u;
      std::array<unsigned, kQueue> queue_lanes;
      // Front to back: the lanes' walk counters after each queued plane, so that a lane that
      // terminates there keeps the counts of its walk up to that plane only.
      std::array<VI, kQueue> queue_counts;
      const int x_end = std::min(W, (tx + 1) * T), y_end = std::min(H, (ty + 1) * T);
      // The planes that may hold a fetched sample of this tile: where the box of the tile's samples
      // on the plane (that of the four corner rays' points, padded by 1e-3 voxel against the
      // rounding of both) touches a live cell, clamped as the samples' voxels are. Each packet then
      // walks these planes only (with skipping; every plane without it or with a distorted camera).
      WalkGrid tile_grid = grid;
      // The planes of the pixels [x_lo, x_hi] x [y_lo, y_hi] (inclusive) from their corner rays.
      auto bound_planes = [&](TilePlanes& tile_planes, int x_lo, int y_lo, int x_hi, int y_hi) {
        tile_planes.stack = &stack, tile_planes.live_sums = live_sums_.data(), tile_planes.dims = dims;
        tile_planes.cells = cells_, tile_planes.cell_shift = cell_shift;
        tile_planes.reset(stack.count);
        bool ok = true;
        for (int c = 0; c < 4; ++c) {
          const CameraRay r = rays.generate_ray(c & 1 ? x_hi : x_lo, c & 2 ? y_hi : y_lo);
          const double cos_psi = stack.n.dot(r.direction);
          ok = ok && r.ok && cos_psi > 0;
          tile_planes.along[std::size_t(c)] = (r.direction / cos_psi).cwiseProduct(inv_spacing);
          tile_planes.base[std::size_t(c)] =
              (r.origin - origin).cwiseProduct(inv_spacing) - stack.n.dot(r.origin) * tile_planes.along[std::size_t(c)];
        }
        if (!ok) tile_planes.all();
      };
      const int blocks_x = (x_end - tx * T + block_x - 1) / block_x,
                blocks_y = (y_end - ty * T + block_y - 1) / block_y;
      // Per block of the tile (block_x x block_y pixels), bounded when a packet first walks there.
      std::vector<TilePlanes> block_planes(skip && tile_bounds ? std::size_t(blocks_x * blocks_y) : 0);
      for (int y0 = ty * T; y0 < y_end; y0 += 2)
        for (int x0 = tx * T; x0 < x_end; x0 += kLanesX) {
          VU GQ0[3] = {}, DQ[3] = {};  // each lane's first position and move per plane (32.32 fixed point)
          VD ex = splat(1);
          VI u0 = zero, ns = zero, alive = zero;
          // The linear kind: each lane's last visible α and its corrected value (as per ray).
          VF last_a = splatf(-1), last_ac = splatf(0), ex_f = splatf(1);
          VD O[3] = {}, V[3] = {}, TOFF = splat(ray_frame.t_offset), COSPSI = splat(1);  // each lane's ray
          VF TO_EYE[3] = {};                                                             // -V in float (the lighting's)
          {
            // The lanes' rays and planes (ray_setup.h: each lane the bits of its ray alone).
            VD xs, ys;
            VI in_tile;
            for (int l = 0; l < kLanes; ++l) {
              const int x = x0 + l % kLanesX, y = y0 + l / kLanesX;
              xs[l] = x, ys[l] = y, in_tile[l] = x < x_end && y < y_end ? -1 : 0;
            }
            if (pinhole_rays) {
              ray_setup::pinhole_direction(ray_frame, xs, ys, V);
            } else {
              for (int a = 0; a < 3; ++a) V[a] = splat(stack.n[a]);
              for (int l = 0; l < kLanes; ++l)
                if (in_tile[l]) {
                  const Eigen::Vector3d d = rays.generate_ray(xs[l], ys[l]).direction;
                  for (int a = 0; a < 3; ++a) V[a][l] = d[a];
                }
            }
            const ray_setup::Rays<VD> rr = ray_setup::rays_from(ray_frame, V);
            alive = in_tile & (rr.k_first <= rr.k_last);
            const VL live_l = wide(alive);
            cnt.rays += count(alive);
            for (int a = 0; a < 3; ++a) {
              O[a] = splat(eye[a]);
              GQ0[a] = live_l ? rr.g0[a] : VU{}, DQ[a] = live_l ? rr.dg[a] : VU{};
            }
            COSPSI = select(live_l, rr.cos_psi, splat(1));
            ex = select(live_l, rr.exponent, splat(1));
            ex_f = __builtin_convertvector(ex, VF);
            for (int a = 0; a < 3; ++a) TO_EYE[a] = -__builtin_convertvector(V[a], VF);
            u0 = select(alive, kFrontToBack ? -rr.k_last : rr.k_first, zero);
            ns = select(alive, rr.k_last - rr.k_first + 1, zero);
          }
          // The constant kinds' corrected α per lane and piece, for the TFs the mask uses, as the
          // scalar loop computes it per ray (corrected_alpha on the lanes; exact_pow: std::pow lane by lane).
          for (int t = 0; t < 4; ++t) {
            const InlineTf& tf = tfs[std::size_t(t)];
            if (!tf_used_[std::size_t(t)] || tf.linear()) continue;
            acp[std::size_t(t * max_pieces)] = splatf(0);
            for (int p = 1; p < tf.pieces(); ++p) {
              const double a = tf.piece_alpha(p);
              VD c = splat(a);
              if (exact_pow) {
                for (int l = 0; l < kLanes; ++l)
                  if (ex[l] != 1.0) c[l] = 1.0 - std::pow(1.0 - a, ex[l]);
              } else {
                const VL corr = ex != 1.0;
                c = select(corr, lane_math::corrected_alpha(splat(a), ex, corr), c);
              }
              acp[std::size_t(t * max_pieces + p)] = __builtin_convertvector(c, VF);
            }
          }
          VF Cr = splatf(0), Cg = splatf(0), Cb = splatf(0), A = splatf(0);
          // Counters per lane (a mask is -1 where true: subtracting it counts), summed after the packet.
          VI n_fetched = zero, n_classified = zero;
          // Blinn-Phong on the lanes (shade()'s arithmetic: sums of three squares or products by
          // dot3, normalisation as v / sqrt(|v|²) where
          // |v|² > 0): the gradient's three encoded channels of each corner by one 32-bit gather
          // (grad_words_), filtered as VolumeSamples::trilinear_cell filters each channel; the
          // specular term by lane_math::int_pow (an integer exponent) or lane_math::pow on the lanes, as
          // shade() computes it per ray (slicing_specular_power; exact_pow:
          // std::pow lane by lane, which was a fifth of the combined mode's frame; 0 where its base is
          // 0 and the exponent > 0: pow's exact +0). Lanes in vis only, the gradient read in the lanes `read`
          // (a superset of vis that does not wait for the sample's TF); p the world points, to_eye the rays'
          // directions negated.
          auto shade_lanes = [&](VI vis, VI read, const VI(&ii)[3], const VF(&w)[3], const VF(&p)[3],
                                 const VF(&to_eye)[3], VF& cr, VF& cg, VF& cb) {
            VI o0[3], o1[3];
            for (int a = 0; a < 3; ++a) {
              o0[a] = select(read, clamp(ii[a], cell_max[a]) * gstr[a], zero);
              o1[a] = select(read, clamp(ii[a] + 1, cell_max[a]) * gstr[a], zero);
            }
            const VF one_f = splatf(1.0f);
            VF vx[2][2][2][3];  // [x][y][z][channel]
            for (int xx = 0; xx < 2; ++xx)
              for (int yy = 0; yy < 2; ++yy)
                for (int zz = 0; zz < 2; ++zz) {
                  const VI word =
                      gather_i32(grad_words, (xx ? o1[0] : o0[0]) + (yy ? o1[1] : o0[1]) + (zz ? o1[2] : o0[2]));
                  for (int ch = 0; ch < 3; ++ch)
                    vx[xx][yy][zz][ch] = __builtin_convertvector((word >> (8 * ch)) & 255, VF);
                }
            VF gd[3], gw[3];
            for (int ch = 0; ch < 3; ++ch) {
              const VF c00 = vx[0][0][0][ch] * (one_f - w[0]) + vx[1][0][0][ch] * w[0];
              const VF c10 = vx[0][1][0][ch] * (one_f - w[0]) + vx[1][1][0][ch] * w[0];
              const VF c01 = vx[0][0][1][ch] * (one_f - w[0]) + vx[1][0][1][ch] * w[0];
              const VF c11 = vx[0][1][1][ch] * (one_f - w[0]) + vx[1][1][1][ch] * w[0];
              const VF e =
                  ((c00 * (one_f - w[1]) + c10 * w[1]) * (one_f - w[2]) + (c01 * (one_f - w[1]) + c11 * w[1]) * w[2]) *
                  grad_channel_scale;
              gd[ch] = (2.0f * e - 1.0f) * grad_scale_f;
              gw[ch] = gd[ch] * inv_spacing_f[ch];
            }
            auto sq = [&](const VF(&x)[3]) { return dot3(x, x); };
            const VF gw2 = sq(gw);
            const VI lit_l = vis & (sqrt(sq(gd)) > gate_f) & (sqrt(gw2) > 0.0f);
            if (!any(lit_l)) return;
            VF nrm[3], ld[3], hd[3];
            const VF gwn = sqrt(gw2);
            for (int a = 0; a < 3; ++a) nrm[a] = -(gw[a] / gwn), ld[a] = light_pos_f[a] - p[a];
            const VF l2 = sq(ld), ln = sqrt(l2);
            for (int a = 0; a < 3; ++a) ld[a] = select(l2 > 0.0f, ld[a] / ln, ld[a]), hd[a] = ld[a] + to_eye[a];
            const VF h2 = sq(hd), hn = sqrt(h2);
            for (int a = 0; a < 3; ++a) hd[a] = select(h2 > 0.0f, hd[a] / hn, hd[a]);
            const VF nl = dot3(nrm, ld), nh = dot3(nrm, hd);
            const VF diff = select(nl < 0.0f, splatf(0), nl);
            const VF base = select(nh < 0.0f, splatf(0), nh);
            VF spec = splatf(0);
            const VI needs_pow = light.exponent > 0 ? lit_l & (base != 0.0f) : lit_l;
            if (exact_pow) {
              for (unsigned b = bits(needs_pow); b != 0; b &= b - 1) {
                const int l = __builtin_ctz(b);
                spec[l] = float(power(double(base[l]), light.exponent));
              }
            } else if (any(needs_pow)) {
              const VD base_d = __builtin_convertvector(base, VD);
              const VD power_d = lane_math::specular_power(base_d, int_exponent, light.exponent);
              spec = select(needs_pow, __builtin_convertvector(power_d, VF), spec);
            }
            const VF k = ambient_f + diffuse_f * diff, sp = specular_f * spec;
            cr = select(lit_l, cr * k + sp, cr), cg = select(lit_l, cg * k + sp, cg),
            cb = select(lit_l, cb * k + sp, cb);
          };
          WalkLanes walk;
          for (int a = 0; a < 3; ++a) walk.dg[a] = DQ[a];
          walk.u0 = u0, walk.uend = u0 + ns, walk.alive = alive, walk.done = zero;
          walk.visited = zero;
          VI n_lane_samples = ns;
          int u_first = std::numeric_limits<int>::max(), u_last = std::numeric_limits<int>::min();
          for (int l = 0; l < kLanes; ++l)
            if (alive[l]) u_first = std::min(u_first, u0[l]), u_last = std::max(u_last, walk.uend[l] - 1);
          // The lanes' positions at u_first (phase B recomputes each plane's from these).
          VU GS[3];
          for (int a = 0; a < 3; ++a) GS[a] = GQ0[a] + __builtin_convertvector(splati(u_first) - u0, VU) * DQ[a];
          for (int a = 0; a < 3; ++a) walk.g[a] = GS[a];
          walk.u = u_first, walk.u_last = u_last;
          if (skip && tile_bounds) {
            const int bx = (x0 - tx * T) / block_x, by = (y0 - ty * T) / block_y;
            TilePlanes& planes = block_planes[std::size_t(by * blocks_x + bx)];
            if (planes.stack == nullptr) {
              const int xb = tx * T + bx * block_x, yb = ty * T + by * block_y;
              bound_planes(planes, xb, yb, std::min(xb + block_x, x_end) - 1, std::min(yb + block_y, y_end) - 1);
            }
            tile_grid.planes = &planes;
          }
          VI& done = walk.done;
          while (walk.u <= walk.u_last) {
            // Phase A: the walk, until the queue is full or the lanes' planes end.
            const int queued =
                walk_planes<kFrontToBack>(tile_grid, walk, kFrontToBack ? kQueueFrontToBack : kQueue, queue_u.data(),
                                          queue_lanes.data(), kFrontToBack ? queue_counts.data() : nullptr);
            // Phase B: the queued planes' samples.
            for (int q = 0; q < queued; ++q) {
              const int Uq = queue_u[std::size_t(q)];
              VI sample = (splati(int(queue_lanes[std::size_t(q)])) & lane_bit) != 0;
              if constexpr (kFrontToBack) {
                sample &= ~done;
                if (!any(sample)) continue;
              }
              const VI step = splati(Uq) - u0;
              const std::uint64_t s = std::uint64_t(std::int64_t(Uq) - u_first);
              const VU gq[3] = {GS[0] + s * DQ[0], GS[1] + s * DQ[1], GS[2] + s * DQ[2]};
              const VI ii[3] = {fixed::floor_voxel(gq[0]), fixed::floor_voxel(gq[1]), fixed::floor_voxel(gq[2])};
              const VI ic[3] = {clamp(ii[0], cell_max[0]), clamp(ii[1], cell_max[1]), clamp(ii[2], cell_max[2])};
              n_fetched -= sample;
              const int k = kFrontToBack ? -Uq : Uq;  // the plane (the same for every lane)
              VI m = one;
              // The world point o + t_k v of each lane (the scalar loop's p) where the light needs it.
              VD P[3];
              if constexpr (kLit) {
                const VD tk = (splat(stack.depth(k)) - TOFF) / COSPSI;
                for (int a = 0; a < 3; ++a) P[a] = O[a] + tk * V[a];
              }
              const VF w[3] = {fixed::weight(gq[0]), fixed::weight(gq[1]), fixed::weight(gq[2])};
              // The lanes whose stencil is read: those of the walk, the mask's cuts included, so that
              // the volume's gathers need not wait for the mask's (a cut lane's values are not used).
              const VI read = sample;
              if constexpr (kMasked) {
                // MaskIndexLookup::lookup on the lanes (its float arithmetic; the bytes by one gather).
                VI cell = zero;
                for (int a = 2; a >= 0; --a) {
                  const std::size_t ax = std::size_t(a);
                  const float n = float(mask_index.n[ax]);
                  const VF f =
                      floor((__builtin_convertvector(ii[a], VF) + w[a]) * mask_index.scale[ax] + mask_index.offset[ax]);
                  const VI ci =
                      __builtin_convertvector(select(f < 0.0f, splatf(0), select(f >= n, splatf(n - 1), f)), VI);
                  cell = a == 2 ? ci : ci + mask_index.n[ax] * cell;
                }
                m = select(sample, gather_u8(mask_index.cells, select(sample, cell, zero)), one);
                sample &= m != 0;
              }
              n_classified -= sample;
              if (!any(sample)) continue;
              // Trilinear fetch (VolumeSamples::trilinear_cell's arithmetic; offset 0 in idle lanes).
              VI o0[3], o1[3];
              for (int a = 0; a < 3; ++a) {
                o0[a] = select(read, ic[a] * str[a], zero);
                o1[a] = select(read, clamp(ii[a] + 1, cell_max[a]) * str[a], zero);
              }
              const VF one_f = splatf(1.0f);
              // The corners v[y][z] at x0 and x1 (offsets y0/y1, z0/z1). Float samples with x fastest
              // and no lane at the x border: each x0, x1 pair by one 64-bit gather (the same values).
              VF vx0[2][2], vx1[2][2];
              bool paired = false;
              if constexpr (std::is_same_v<std::remove_cv_t<std::remove_pointer_t<decltype(samples.data)>>, float>) {
                paired = x_packed && !any(read & ((ii[0] < 0) | (ii[0] >= cell_max[0])));
                if (paired)
                  for (int yy = 0; yy < 2; ++yy)
                    for (int zz = 0; zz < 2; ++zz)
                      gather_pairs(samples.data, o0[0] + (yy ? o1[1] : o0[1]) + (zz ? o1[2] : o0[2]), vx0[yy][zz],
                                   vx1[yy][zz]);
              }
              if (!paired)
                for (int yy = 0; yy < 2; ++yy)
                  for (int zz = 0; zz < 2; ++zz) {
                    const VI oyz = (yy ? o1[1] : o0[1]) + (zz ? o1[2] : o0[2]);
                    vx0[yy][zz] = gather(samples.data, o0[0] + oyz);
                    vx1[yy][zz] = gather(samples.data, o1[0] + oyz);
                  }
              const VF c00 = vx0[0][0] * (one_f - w[0]) + vx1[0][0] * w[0];
              const VF c10 = vx0[1][0] * (one_f - w[0]) + vx1[1][0] * w[0];
              const VF c01 = vx0[0][1] * (one_f - w[0]) + vx1[0][1] * w[0];
              const VF c11 = vx0[1][1] * (one_f - w[0]) + vx1[1][1] * w[0];
              const VF f =
                  ((c00 * (one_f - w[1]) + c10 * w[1]) * (one_f - w[2]) + (c01 * (one_f - w[1]) + c11 * w[1]) * w[2]) *
                  samples.scale;
              const VF fn_f = (f - lo_f) * inv_range_f;  // the linear kind's
              VF a = splatf(0), ac = splatf(0), cr = splatf(0), cg = splatf(0), cb = splatf(0);
              for (int t = 0; t < (kMasked ? 4 : 1); ++t) {
                const VI sel = kMasked ? sample & (m == t + 1) : sample;
                if (!any(sel)) continue;
                const InlineTf& tf = tfs[std::size_t(t)];
                if (tf.linear()) {
                  // The linear kind on the lanes in float (LaneLinearTf: InlineTf's bits); the corrected
                  // α where a visible α changed (the scalar loop's last α), by
                  // lane_math::corrected_alpha_f on the lanes (exact_pow: std::pow lane by lane).
                  const LaneLinearTf& lane_tf = *lane_tfs[std::size_t(t)];
                  LaneLinearTf::Seg seg;
                  const VF ta = lane_tf.alpha(fn_f, seg);
                  if (!any(sel & (ta > 0))) {  // none of its lanes visible: colour and α' unused
                    a = select(sel, ta, a);
                    continue;
                  }
                  VF tr, tg, tb;
                  lane_tf.rgb(fn_f, seg, tr, tg, tb);
                  const VI corr = sel & (ta > 0) & (ex_f != 1.0f);
                  const VI fresh = corr & (ta != last_a);
                  if (exact_pow) {
                    for (unsigned b = bits(fresh); b != 0; b &= b - 1) {
                      const int l = __builtin_ctz(b);
                      last_ac[l] = correct_f(ta[l], ex_f[l]);
                    }
                  } else if (any(fresh)) {
                    last_ac = select(fresh, lane_math::corrected_alpha_f(ta, ex_f, fresh), last_ac);
                  }
                  last_a = select(fresh, ta, last_a);
                  a = select(sel, ta, a), ac = select(sel, select(corr, last_ac, ta), ac);
                  cr = select(sel, tr, cr), cg = select(sel, tg, cg), cb = select(sel, tb, cb);
                  continue;
                }
                // The constant kind: the range tests in double (TfRange::contains), the piece's
                // values in float (InlineTf's), its corrected α per lane from the packet's table.
                const VD fn = (__builtin_convertvector(f, VD) - lo_) * inv_range;
                VF pa = splatf(0), pr = splatf(0), pg = splatf(0), pb = splatf(0),
                   pac = acp[std::size_t(t * max_pieces)];
                for (int i = tf.ranges() - 1; i >= 0; --i) {
                  const double rl = tf.range_lo(i), rh = tf.range_hi(i);
                  const VL above = tf.range_lo_closed(i) ? VL(fn >= rl) : VL(fn > rl);
                  const VL below = tf.range_hi_closed(i) ? VL(fn <= rh) : VL(fn < rh);
                  const VI in = narrow(above & below);
                  const Eigen::Vector3f& rgb = tf.piece_rgb(i + 1);
                  pa = select(in, splatf(float(tf.piece_alpha(i + 1))), pa);
                  pr = select(in, splatf(rgb.x()), pr), pg = select(in, splatf(rgb.y()), pg);
                  pb = select(in, splatf(rgb.z()), pb);
                  pac = select(in, acp[std::size_t(t * max_pieces + i + 1)], pac);
                }
                a = select(sel, pa, a), ac = select(sel, pac, ac);
                cr = select(sel, pr, cr), cg = select(sel, pg, cg), cb = select(sel, pb, cb);
              }
              const VI vis = sample & (a > 0);
              if (!any(vis)) continue;
              if constexpr (kLit) {
                // Blinn-Phong in float (shade()'s; the world points and directions rounded to float).
                const VF pf[3] = {__builtin_convertvector(P[0], VF), __builtin_convertvector(P[1], VF),
                                  __builtin_convertvector(P[2], VF)};
                if (grad_words != nullptr) {
                  shade_lanes(vis, read, ii, w, pf, TO_EYE, cr, cg, cb);
                } else {
                  for (int l = 0; l < kLanes; ++l) {
                    if (!vis[l]) continue;
                    Eigen::Vector3f c(cr[l], cg[l], cb[l]);
                    shade(c, ii[0][l], ii[1][l], ii[2][l], w[0][l], w[1][l], w[2][l],
                          Eigen::Vector3f(pf[0][l], pf[1][l], pf[2][l]),
                          Eigen::Vector3f(TO_EYE[0][l], TO_EYE[1][l], TO_EYE[2][l]));
                    cr[l] = c.x(), cg[l] = c.y(), cb[l] = c.z();
                  }
                }
              }
              if constexpr (kFrontToBack) {
                const VF wgt = (1.0f - A) * ac;
                Cr = select(vis, Cr + wgt * cr, Cr), Cg = select(vis, Cg + wgt * cg, Cg),
                Cb = select(vis, Cb + wgt * cb, Cb);
                A = select(vis, A + wgt, A);
                const VI term = vis & (A >= stop_alpha);
                if (any(term)) {
                  cnt.terminated += count(term);
                  n_lane_samples = select(term, step + 1, n_lane_samples);
                  walk.visited = select(term, queue_counts[std::size_t(q)], walk.visited);
                  done |= term;
                }
                continue;
              }
              if (mode == SlicingMode::kBlend) {
                if (blend_op == BlendOperator::kOver) {
                  Cr = select(vis, ac * cr + (1.0f - ac) * Cr, Cr), Cg = select(vis, ac * cg + (1.0f - ac) * Cg, Cg);
                  Cb = select(vis, ac * cb + (1.0f - ac) * Cb, Cb);
                } else {
                  Cr = select(vis, Cr + ac * cr, Cr), Cg = select(vis, Cg + ac * cg, Cg),
                  Cb = select(vis, Cb + ac * cb, Cb);
                }
                A = select(vis, ac + (1.0f - ac) * A, A);
              } else {
                const VI wins = vis & (a >= A);
                if (mode == SlicingMode::kCombined) {
                  const VI rest = vis & ~wins;
                  Cr = select(rest, ac * cr + (1.0f - ac) * Cr, Cr), Cg = select(rest, ac * cg + (1.0f - ac) * Cg, Cg);
                  Cb = select(rest, ac * cb + (1.0f - ac) * Cb, Cb);
                }
                Cr = select(wins, cr, Cr), Cg = select(wins, cg, Cg), Cb = select(wins, cb, Cb);
                A = select(wins, a, A);
              }
            }
            if (kFrontToBack && !any(alive & ~done)) break;
          }
          cnt.samples += hsum(n_lane_samples);
          cnt.visited += hsum(walk.visited);
          cnt.skipped += hsum(n_lane_samples) - hsum(n_fetched);
          cnt.classified += hsum(n_classified);
          for (int l = 0; l < kLanes; ++l) {
            const int x = x0 + l % kLanesX, y = y0 + l / kLanesX;
            if (x >= x_end || y >= y_end) continue;
            const Eigen::Vector3d C(Cr[l], Cg[l], Cb[l]);
            const double A_l = A[l];  // (the background in double, as per ray)
            const Eigen::Vector3d out =
                mode == SlicingMode::kBlend ? Eigen::Vector3d(C + (1 - A_l) * background) : (A_l > 0 ? C : background);
            write_pixel(x, y, out, A_l);
          }
        }
      for (const auto& b : block_planes) cnt.cell_tests += b.tests;
      counts[std::size_t(ty) * tiles_x + tx] = cnt;
    };
    auto run_tiles = [&](auto lit_c, auto masked_c, auto ftb_c) {
      auto tile = [&](int tx, int ty) {
        if (use_packets)
          do_packet_tile(tx, ty, lit_c, masked_c, ftb_c);
        else
          do_tile(tx, ty, lit_c, masked_c, ftb_c);
      };
      if (s_.parallel)
        tbb::parallel_for(tbb::blocked_range2d<int>(0, tiles_y, 1, 0, tiles_x, 1), [&](const auto& r) {
          for (int ty = r.rows().begin(); ty < r.rows().end(); ++ty)
            for (int tx = r.cols().begin(); tx < r.cols().end(); ++tx) tile(tx, ty);
        });
      else
        for (int ty = 0; ty < tiles_y; ++ty)
          for (int tx = 0; tx < tiles_x; ++tx) tile(tx, ty);
    };
    using T0 = std::false_type;
    using T1 = std::true_type;
    auto with_ftb = [&](auto lit_c, auto masked_c) {
      if (front_to_back)
        run_tiles(lit_c, masked_c, T1{});
      else
        run_tiles(lit_c, masked_c, T0{});
    };
    auto with_mask = [&](auto lit_c) {
      if (use_mask)
        with_ftb(lit_c, T1{});
      else
        with_ftb(lit_c, T0{});
    };
    if (lit)
      with_mask(T1{});
    else
      with_mask(T0{});
  });
  frame.stats.render_ms = ms_since(t0);
  for (const auto& c : counts) {
    frame.stats.rays += c.rays;
    frame.stats.samples += c.samples;
    frame.stats.classified += c.classified;
    frame.stats.skipped += c.skipped;
    frame.stats.terminated += c.terminated;
    frame.stats.visited += c.visited;
    frame.stats.cell_tests += c.cell_tests;
  }
  const auto t1 = std::chrono::steady_clock::now();
  if (!post_clamp) apply_bloom(frame.raw, s_.post, frame.rgb);
  frame.stats.post_ms = ms_since(t1);
}

double slicing_pow(double x, double y) { return lane_math::pow(x, y); }

double slicing_corrected_alpha(double a, double e) { return lane_math::corrected_alpha(a, e); }

namespace {

/// out[i] = the i-th lane of correct(a, e, need) over packets of kLanes (V: VD or VF, M its mask;
/// the last packet padded with a = 0, e = 1 and its idle lanes not needed). Also the specular power's
/// lanes (a the base, e the exponent).
template <class V, class M, class T, class Correct>
void corrected_alpha_on_lanes(const char* name, std::span<const T> a, std::span<const T> e, std::span<T> out,
                              Correct correct) {
  if (e.size() != a.size() || out.size() != a.size())
    throw std::invalid_argument(fmt::format("{}: spans of different sizes", name));
  using packet::kLanes;
  for (std::size_t i = 0; i < a.size(); i += kLanes) {
    V av = V{}, ev = V{} + T(1);
    M need{};
    for (std::size_t l = 0; l < kLanes && i + l < a.size(); ++l) av[l] = a[i + l], ev[l] = e[i + l], need[l] = -1;
    const V r = correct(av, ev, need);
    for (std::size_t l = 0; l < kLanes && i + l < a.size(); ++l) out[i + l] = r[l];
  }
}

}  // namespace

void slicing_corrected_alpha_lanes(std::span<const double> a, std::span<const double> e, std::span<double> out) {
  corrected_alpha_on_lanes<packet::VD, packet::VL>(
      "slicing_corrected_alpha_lanes", a, e, out,
      [](packet::VD x, packet::VD y, packet::VL need) { return lane_math::corrected_alpha(x, y, need); });
}

double slicing_specular_power(double x, double y) {
  return lane_math::specular_power(x, lane_math::int_exponent(y), y);
}

void slicing_specular_power_lanes(std::span<const double> x, double y, std::span<double> out) {
  const std::vector<double> ys(x.size(), y);
  const int n = lane_math::int_exponent(y);
  corrected_alpha_on_lanes<packet::VD, packet::VL>(
      "slicing_specular_power_lanes", x, std::span<const double>(ys), out,
      [n, y](packet::VD b, packet::VD, packet::VL) { return lane_math::specular_power(b, n, y); });
}

float slicing_corrected_alpha_f(float a, float e) { return lane_math::corrected_alpha_f(a, e); }

void slicing_corrected_alpha_f_lanes(std::span<const float> a, std::span<const float> e, std::span<float> out) {
  corrected_alpha_on_lanes<packet::VF, packet::VI>(
      "slicing_corrected_alpha_f_lanes", a, e, out,
      [](packet::VF x, packet::VF y, packet::VI need) { return lane_math::corrected_alpha_f(x, y, need); });
}

TfValue slicing_linear_tf_value(const TransferFunction& tf, float v) {
  if (tf.kind() != TfKind::kPiecewiseLinear)
    throw std::invalid_argument("slicing_linear_tf_value: the transfer function is not piecewise linear");
  const InlineTf inline_tf(tf);
  FloatCurve::Segment seg;
  TfValue out;
  out.alpha = inline_tf.alpha(v, seg);
  out.rgb = inline_tf.rgb(v, seg).cast<double>();
  return out;
}

SlicingFrame render_slicing(const Volume& volume, const Camera& camera, const SlicingSettings& settings) {
  return SlicingRenderer(volume, settings).render(camera);
}

std::vector<std::pair<std::string, std::string>> describe_vsi(const SlicingSettings& s, const Volume& volume,
                                                              const Camera& camera) {
  std::vector<std::pair<std::string, std::string>> r;
  auto add = [&](const std::string& k, const std::string& v) { r.emplace_back("vsi." + k, v); };
  auto num = [](double x) { return fmt::format("{:.17g}", x); };
  add("data.norm_source",
      s.value_range ? fmt::format("given [{}, {}]", num(s.value_range->first), num(s.value_range->second)) : "scanned");
  add("data.internal_bits", sample_type_name(volume.type()));
  add("grad.radius", std::to_string(s.gradient.radius));
  add("grad.neighbourhood", s.gradient.neighbourhood == GradientNeighbourhood::kBall ? "ball" : "cube");
  add("grad.encode", "1/2 + 1/2 g / max|g|");
  add("grad.bits", std::to_string(s.gradient.bits));
  add("grad.boundary", "clamp");
  add("grad.used", slicing_needs_gradients(s) ? "true" : "false (unlit Blend)");
  add("tf.count", "4");
  for (int i = 0; i < 4; ++i) {
    const auto& tf = s.tfs[std::size_t(i)];
    add(fmt::format("tf{}.kind", i + 1),
        tf.kind() == TfKind::kPiecewiseLinear ? "piecewise_linear" : "piecewise_constant");
    add(fmt::format("tf{}.name", i + 1), tf.name());
  }
  add("tf.resolution/curve",
      "exact: control points evaluated per sample (no table), piecewise linear, in float "
      "(the sample's precision; within 8 2^-24 of the curve in double)");
  if (s.mask.empty()) {
    add("mask.resolution", "none (TF 1 everywhere)");
  } else {
    const auto d = s.mask.dims();
    add("mask.resolution", fmt::format("{} x {} x {}", d[0], d[1], d[2]));
    const auto h = s.mask.histogram();
    add("mask.histogram", fmt::format("[{}, {}, {}, {}, {}]", h[0], h[1], h[2], h[3], h[4]));
  }
  add("mask.filter",
      "nearest, the cell from the sample's index coordinates in float (its faces within ~2^-23 "
      "(|g| s + |o|) cells of the world point's)");
  add("mask.object_shape", "box | sphere | ellipsoid (normalised box coordinates)");
  add("slice.normal", "centre - camera");
  add("slice.normalise_n", "true");
  add("slice.d_range", s.d_range == SliceRange::kTight ? "tight corner range" : "conservative +-D");
  add("slice.qc_map", "dd = QC * h0");
  add("slice.quality_class", num(s.quality_class));
  add("slice.spacing", num(slice_spacing(s.quality_class, volume.spacing())));
  add("slice.order", "back to front");
  add("slice.positions", s.exact_positions
                             ? "exact: o + t_k v per sample"
                             : "incremental: g_0 + j dg per ray in 32.32 fixed point (< (j + 1) 2^-33 voxel)");
  if (const auto* p = std::get_if<Pinhole>(&camera))
    add("camera.fov", fmt::format("{:.6g} deg (vertical)", 2 * std::atan(0.5 * p->height / p->fy) * 180 / M_PI));
  add("cpu.realisation", "per-pixel ray-plane sampling");
  add("cpu.packets", s.simd && !s.exact_positions
                         ? fmt::format("{} x 2 pixel blocks on {} SIMD lanes, a walk then a fetch phase (the same "
                                       "image as one ray at a time)",
                                       packet::kLanesX, packet::kLanes)
                         : "off (one ray at a time)");
  add("cpu.pow", s.exact_pow
                     ? "std::pow in double, rounded to float"
                     : "the linear TFs' corrected alpha by slicing_corrected_alpha_f in float (within 4 2^-24), "
                       "the constant TFs' per ray and piece by slicing_corrected_alpha (within (4 + e) 2^-53 "
                       "of 1 - std::pow(1 - a, e)), the specular power by slicing_specular_power (x^n by "
                       "squarings for an integer n, else slicing_pow), rounded to float");
  add("cpu.precision",
      "float: the TF, the corrected alpha, Blinn-Phong and the compositing (C, A); the "
      "background added in double");
  add("mode", slicing_mode_name(s.mode));
  add("blend.operator", s.blend == BlendOperator::kOver ? "over" : "additive");
  add("blend.opacity_correction", s.opacity_correction ? "on, dref = h0, along-ray spacing dd / cos psi" : "off");
  add("mip.rule", "max alpha wins");
  add("combined.rule", "OUR INTERPRETATION (spec 2.6): a >= A_max replaces, else over-blends the lit colour");
  add("light.model", fmt::format("Blinn-Phong ambient {} diffuse {} specular {} exponent {}", num(s.light.ambient),
                                 num(s.light.diffuse), num(s.light.specular), num(s.light.exponent)));
  add("light.position", fmt::format("eye + camera-frame ({}, {}, {}) box diagonals", num(s.light.light_camera.x()),
                                    num(s.light.light_camera.y()), num(s.light.light_camera.z())));
  add("light.gate", num(s.light.gate));
  add("shade.modes", s.lit_blend ? "mip, combined and blend" : "mip and combined");
  add("post.adjust", fmt::format("contrast {} brightness {} gamma {}", num(s.post.adjust.contrast),
                                 num(s.post.adjust.brightness), num(s.post.adjust.gamma)));
  add("post.bloom", s.post.enabled ? "on" : "off");
  add("post.threshold", num(s.post.threshold) + " of Rec. 709 luminance");
  add("post.sigma/radius", fmt::format("{} half-res px, radius ceil(3 sigma)", num(s.post.sigma)));
  add("post.bloom_blend", fmt::format("additive, gain {}", num(s.post.gain)));
  add("post.render_target", "float32");
  add("skip_empty", s.skip_empty ? fmt::format("{}^3 cells, runs of empty planes jumped{}{}, exact (same image)",
                                               s.skip_cell, s.live_runs ? " and of live planes run" : "",
                                               s.skip_voxels ? ", voxel stencils no TF sees not fetched" : "")
                                 : "off");
  add("blend.early_termination",
      s.early_termination > 0
          ? (s.mode == SlicingMode::kBlend && s.blend == BlendOperator::kOver
                 ? fmt::format("front to back, stop at A >= {} (beyond the source)", num(s.early_termination))
                 : "off (only Blend over; ignored in this mode)")
          : "off (the source's back-to-front order)");
  return r;
}

}  // namespace meltlab::render
