// Silhouette rasterizer (see raster/silhouette.h for the conventions).
//
// Pipeline of one frame:
//  1. every vertex is projected to homogeneous "grid" coordinates (xh, yh, w): the grid is the
//     image (or, with k x k supersampling, the k-times finer sample grid, whose integer points
//     are the sub-sample positions), in which (xh / w, yh / w) is the position; a vertex inside
//     the guard band and in front of the camera is snapped to 1/256 of a grid pixel;
//  2. every live triangle with three snapped vertices is set up (cull test on its exact integer
//     signed area, vertices sorted by y); the others are clipped in homogeneous coordinates
//     against the guard band and the near plane, then fanned;
//  3. triangles are binned into bands of rows and the bands are filled (in parallel if asked):
//     per row, the first pixel centre on or right of an edge is ceil(N / D) of exact integers,
//     advanced from row to row by an exact integer DDA, so an edge shared by two triangles
//     gives both the same boundary pixel and no pixel centre is counted twice or missed;
//  4. coverage: each band is rasterized on the k-times grid into a per-thread byte buffer and
//     reduced to the fraction of covered samples per pixel;
//  5. distorted pinhole: steps 1-4 render an ideal (undistorted) canvas, resampled through maps
//     built once per renderer.

#include <meltlab/render/raster/silhouette.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace meltlab::render {

namespace {

using i64 = std::int64_t;
using i32 = std::int32_t;

constexpr i64 kSub = 256;             // fixed-point sub-pixel steps per grid pixel
constexpr double kGuard = 524288.0;   // 2^19 grid pixels: |coordinate| bound of snapped vertices
constexpr double kNearZ = 1e-9;       // near plane of a pinhole camera, mesh units
constexpr int kMaxGrid = 1 << 18;     // image (or canvas) size x supersample, well inside the guard band
constexpr int kBinaryBandRows = 32;   // rows per band, binary mask
constexpr int kCoverageBandRows = 8;  // output rows per band, coverage

inline i64 floor_div(i64 a, i64 b) {  // b > 0
  i64 q = a / b;
  if (a % b < 0) --q;
  return q;
}
inline i64 ceil_div(i64 a, i64 b) {  // b > 0
  i64 q = a / b;
  if (a % b > 0) ++q;
  return q;
}

struct Fix {
  i32 x, y;
};

struct Hom {
  double x, y, w;
};

// A triangle ready to fill: vertices sorted by y (fixed point), grid rows [r0, r1) split at rm
// (rows above rm use the edge 0-1, rows from rm on the edge 1-2; the long edge 0-2 is on the
// other side). mid_left: vertex 1 lies left of the long edge.
struct Tri {
  i32 x0, y0, x1, y1, x2, y2;
  i32 r0, rm, r1;
  bool mid_left;
};

// For the edge a -> b (a.y < b.y) and grid row r with a.y <= r * kSub < b.y: q = the smallest
// integer x with x * kSub >= the edge's x at y = r * kSub (exact: ceil(N / D) of integers), and
// e = q D - N in [0, D). step() advances one row exactly (integer DDA).
struct Edge {
  i64 q, e, qstep, rstep, D;
  Edge(i64 ax, i64 ay, i64 bx, i64 by, i64 r) {
    const i64 dX = bx - ax, dY = by - ay;
    D = kSub * dY;
    const i64 N = ax * dY + (r * kSub - ay) * dX;  // |.| < 2^59 with coordinates < 2^28
    q = ceil_div(N, D);
    e = q * D - N;
    const i64 dN = kSub * dX;
    qstep = floor_div(dN, D);
    rstep = dN - qstep * D;
  }
  void step() {
    q += qstep;
    e -= rstep;
    if (e < 0) {
      ++q;
      e += D;
    }
  }
};

// Sets up the triangle (a, b, c) (grid fixed point, original orientation) if it is front-facing
// (or culling is off), not degenerate and reaches some grid row and column.
inline void setup_triangle(Fix a, Fix b, Fix c, bool cull, i32 grid_w, i32 grid_h, std::vector<Tri>& out) {
  const i64 area2 = (i64(b.x) - a.x) * (i64(c.y) - a.y) - (i64(b.y) - a.y) * (i64(c.x) - a.x);
  // Image v points down, so a triangle counter-clockwise seen from outside (facing the camera)
  // has a negative signed area in (u, v).
  if (area2 == 0 || (cull && area2 > 0)) return;
  if (a.y > b.y) std::swap(a, b);
  if (b.y > c.y) std::swap(b, c);
  if (a.y > b.y) std::swap(a, b);
  const i64 min_x = std::min({a.x, b.x, c.x}), max_x = std::max({a.x, b.x, c.x});
  if (max_x < 0 || min_x > i64(grid_w - 1) * kSub) return;
  i64 r0 = ceil_div(a.y, kSub), rm = ceil_div(b.y, kSub), r1 = ceil_div(c.y, kSub);
  r0 = std::max<i64>(r0, 0);
  r1 = std::min<i64>(r1, grid_h);
  if (r0 >= r1) return;
  rm = std::clamp<i64>(rm, r0, r1);
  const i64 cross = (i64(c.x) - a.x) * (i64(b.y) - a.y) - (i64(c.y) - a.y) * (i64(b.x) - a.x);
  out.push_back(Tri{a.x, a.y, b.x, b.y, c.x, c.y, i32(r0), i32(rm), i32(r1), cross > 0});
}

// Fills grid rows [ra, rb) of the triangle: span(row, x_begin, x_end) for the pixel centres
// x_begin <= x < x_end (clipped to [0, grid_w)), left edges inclusive, right edges exclusive.
template <class Span>
inline void raster(const Tri& t, i32 ra, i32 rb, i32 grid_w, Span&& span) {
  const i32 r0 = std::max(t.r0, ra), r1 = std::min(t.r1, rb);
  if (r0 >= r1) return;
  const i32 rm = std::clamp(t.rm, r0, r1);
  Edge lng(t.x0, t.y0, t.x2, t.y2, r0);
  auto run = [&](Edge& s, i32 from, i32 to) {
    for (i32 r = from; r < to; ++r) {
      i64 l = t.mid_left ? s.q : lng.q;
      i64 h = t.mid_left ? lng.q : s.q;
      l = std::max<i64>(l, 0);
      h = std::min<i64>(h, grid_w);
      if (l < h) span(r, i32(l), i32(h));
      s.step();
      lng.step();
    }
  };
  if (r0 < rm) {
    Edge s(t.x0, t.y0, t.x1, t.y1, r0);
    run(s, r0, rm);
  }
  if (rm < r1) {
    Edge s(t.x1, t.y1, t.x2, t.y2, rm);
    run(s, rm, r1);
  }
}

// Sutherland–Hodgman clip of a convex polygon in homogeneous grid coordinates against
// d(p) >= 0 for each of the planes w >= near, |x| <= G w, |y| <= G w.
int clip_polygon(Hom* poly, int n, double near) {
  Hom tmp[16];
  auto clip = [&](auto dist) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const Hom& p = poly[i];
      const Hom& q = poly[(i + 1) % n];
      const double dp = dist(p), dq = dist(q);
      if (dp >= 0) tmp[m++] = p;
      if ((dp >= 0) != (dq >= 0)) {
        const double t = dp / (dp - dq);
        tmp[m++] = Hom{p.x + t * (q.x - p.x), p.y + t * (q.y - p.y), p.w + t * (q.w - p.w)};
      }
    }
    std::copy(tmp, tmp + m, poly);
    n = m;
  };
  clip([&](const Hom& p) { return p.w - near; });
  if (n) clip([](const Hom& p) { return kGuard * p.w - p.x; });
  if (n) clip([](const Hom& p) { return kGuard * p.w + p.x; });
  if (n) clip([](const Hom& p) { return kGuard * p.w - p.y; });
  if (n) clip([](const Hom& p) { return kGuard * p.w + p.y; });
  return n;
}

inline i32 snap(double g) { return static_cast<i32>(std::nearbyint(std::clamp(g, -kGuard, kGuard) * double(kSub))); }

void check_camera(const Camera& camera) {
  const int w = camera_width(camera), h = camera_height(camera);
  if (w < 1 || h < 1 || w > 65536 || h > 65536)
    throw InputError(fmt::format("silhouette: camera size must be in [1, 65536] (got {}x{})", w, h));
  if (const auto* o = std::get_if<OrthographicTopDown>(&camera)) {
    if (!std::isfinite(o->pixels_per_unit) || o->pixels_per_unit <= 0.0 || !o->centre.allFinite())
      throw InputError("silhouette: orthographic camera needs finite pixels_per_unit > 0 and a finite centre");
    return;
  }
  const auto& p = std::get<Pinhole>(camera);
  bool ok = std::isfinite(p.fx) && std::isfinite(p.fy) && p.fx > 0 && p.fy > 0 && std::isfinite(p.cx) &&
            std::isfinite(p.cy) && p.camera_from_world.matrix().allFinite();
  for (double d : p.distortion) ok = ok && std::isfinite(d);
  if (!ok) throw InputError("silhouette: pinhole camera needs fx, fy > 0 and finite intrinsics, distortion and pose");
}

// o[p] += number of covered samples (bytes 0/1) among row[p k .. p k + k) for p in [p0, p1).
// k = 2, 4, 8 add the bytes of one word at a time (a multiply sums them into the top byte).
inline void add_sample_counts(const std::uint8_t* row, i32 k, i32 p0, i32 p1, float* o) {
  if (k == 4) {
    for (i32 p = p0; p < p1; ++p) {
      std::uint32_t w;
      std::memcpy(&w, row + 4 * p, 4);
      o[p] += float((w * 0x01010101u) >> 24);
    }
  } else if (k == 8) {
    for (i32 p = p0; p < p1; ++p) {
      std::uint64_t w;
      std::memcpy(&w, row + 8 * p, 8);
      o[p] += float((w * 0x0101010101010101ull) >> 56);
    }
  } else if (k == 2) {
    for (i32 p = p0; p < p1; ++p) o[p] += float(row[2 * p] + row[2 * p + 1]);
  } else {
    for (i32 p = p0; p < p1; ++p) {
      int sum = 0;
      for (i32 q = 0; q < k; ++q) sum += row[p * k + q];
      o[p] += float(sum);
    }
  }
}

struct Scratch {
  std::vector<std::uint8_t> buffer;  // coverage band: (band rows * k) x grid width
  std::vector<i32> lo, hi;           // touched column range per sub-row
};

}  // namespace

struct SilhouetteRenderer::Impl {
  Camera camera;
  SilhouetteOptions options;
  int width = 0, height = 0;       // output image
  int canvas_w = 0, canvas_h = 0;  // ideal canvas (== output unless distorted)
  double ox = 0, oy = 0;           // ideal pixel of canvas pixel (0, 0)
  bool distorted = false;
  cv::Mat map_nearest, map_linear1, map_linear2;  // output pixel -> canvas position
  cv::Mat canvas8, canvas32;

  std::vector<Fix> fix;
  std::vector<std::uint8_t> fix_ok;
  std::vector<Tri> tris;
  std::vector<i32> band_offset, band_items;
  tbb::enumerable_thread_specific<Scratch> scratch;

  Impl(Camera c, SilhouetteOptions o) : camera(std::move(c)), options(o) {
    check_camera(camera);
    if (options.supersample < 1 || options.supersample > 16)
      throw InputError(fmt::format("silhouette: supersample must be in [1, 16] (got {})", options.supersample));
    width = camera_width(camera);
    height = camera_height(camera);
    canvas_w = width;
    canvas_h = height;
    if (const auto* p = std::get_if<Pinhole>(&camera); p && p->distorted()) build_maps(*p);
    const int k = options.supersample;
    if (i64(canvas_w) * k > kMaxGrid || i64(canvas_h) * k > kMaxGrid)
      throw InputError(fmt::format("silhouette: image size x supersample must be <= {} (got {}x{} x {})", kMaxGrid,
                                   canvas_w, canvas_h, k));
  }

  void build_maps(const Pinhole& p) {
    distorted = true;
    cv::Mat mx(height, width, CV_32FC1), my(height, width, CV_32FC1);
    std::vector<double> ux(std::size_t(width) * height), uy(ux.size());
    std::vector<std::uint8_t> valid(ux.size());
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
      for (int v = rows.begin(); v < rows.end(); ++v) {
        for (int u = 0; u < width; ++u) {
          const std::size_t i = std::size_t(v) * width + u;
          double x = 0, y = 0;
          valid[i] = undistort_normalized(p.distortion, (u - p.cx) / p.fx, (v - p.cy) / p.fy, x, y);
          ux[i] = p.fx * x + p.cx;
          uy[i] = p.fy * y + p.cy;
        }
      }
    });
    // Canvas: the bounding box of the undistorted positions plus a 2-pixel margin (so bilinear
    // lookups never reach its border), at most the output size again on each side.
    double umin = 0, umax = width - 1, vmin = 0, vmax = height - 1;
    for (std::size_t i = 0; i < ux.size(); ++i) {
      if (!valid[i]) continue;
      umin = std::min(umin, ux[i]);
      umax = std::max(umax, ux[i]);
      vmin = std::min(vmin, uy[i]);
      vmax = std::max(vmax, uy[i]);
    }
    umin = std::max(umin, -double(width));
    vmin = std::max(vmin, -double(height));
    umax = std::min(umax, 2.0 * width);
    vmax = std::min(vmax, 2.0 * height);
    ox = std::floor(umin) - 2;
    oy = std::floor(vmin) - 2;
    canvas_w = int(std::ceil(umax) - ox) + 3;
    canvas_h = int(std::ceil(vmax) - oy) + 3;
    for (int v = 0; v < height; ++v) {
      float* rx = mx.ptr<float>(v);
      float* ry = my.ptr<float>(v);
      for (int u = 0; u < width; ++u) {
        const std::size_t i = std::size_t(v) * width + u;
        const double cu = ux[i] - ox, cv = uy[i] - oy;
        if (valid[i] && cu >= 1 && cv >= 1 && cu <= canvas_w - 2 && cv <= canvas_h - 2) {
          rx[u] = float(cu);
          ry[u] = float(cv);
        } else {  // no ideal position: stays empty
          rx[u] = -100.f;
          ry[u] = -100.f;
        }
      }
    }
    cv::Mat unused;
    cv::convertMaps(mx, my, map_nearest, unused, CV_16SC2, true);
    cv::convertMaps(mx, my, map_linear1, map_linear2, CV_16SC2, false);
  }

  // Step 1: vertices -> snapped grid coordinates (or flagged for the slow path).
  template <class Real>
  void project_vertices(const sim::Vec3<Real>* P, std::size_t nv, std::vector<Hom>* hom_out) {
    fix.resize(nv);
    fix_ok.resize(nv);
    const double k = options.supersample, half = 0.5 * (k - 1);
    auto store = [&](std::size_t i, const Hom& h) {
      const bool ok =
          std::isfinite(h.w) && h.w >= kNearZ && std::abs(h.x) <= kGuard * h.w && std::abs(h.y) <= kGuard * h.w;
      fix_ok[i] = ok;
      if (ok) fix[i] = Fix{snap(h.x / h.w), snap(h.y / h.w)};
      if (hom_out) (*hom_out)[i] = h;
    };
    if (hom_out) hom_out->resize(nv);
    if (const auto* o = std::get_if<OrthographicTopDown>(&camera)) {
      const double cu = 0.5 * (o->width - 1), cv = 0.5 * (o->height - 1);
      for (std::size_t i = 0; i < nv; ++i) {
        const double x = double(P[i].x()), y = double(P[i].y());
        const double u = (x - o->centre.x()) * o->pixels_per_unit + cu;
        const double v = -(y - o->centre.y()) * o->pixels_per_unit + cv;
        store(i, Hom{k * u + half, k * v + half, 1.0});
      }
    } else {
      const auto& p = std::get<Pinhole>(camera);
      const Eigen::Matrix3d R = p.camera_from_world.linear();
      const Eigen::Vector3d t = p.camera_from_world.translation();
      const double cx = p.cx - ox, cy = p.cy - oy;
      for (std::size_t i = 0; i < nv; ++i) {
        const Eigen::Vector3d q = R * P[i].template cast<double>() + t;
        store(i, Hom{k * (p.fx * q.x() + cx * q.z()) + half * q.z(), k * (p.fy * q.y() + cy * q.z()) + half * q.z(),
                     q.z()});
      }
    }
  }

  // Steps 1-2.
  template <class Real>
  void setup(const sim::Vec3<Real>* P, std::size_t nv, const sim::Triangle* F, const std::uint8_t* alive,
             std::size_t nt) {
    const int k = options.supersample;
    const i32 gw = canvas_w * k, gh = canvas_h * k;
    const bool cull = options.cull_backfaces;
    project_vertices(P, nv, nullptr);
    tris.clear();
    bool any_slow = false;
    for (std::size_t f = 0; f < nt; ++f) {
      if (alive && !alive[f]) continue;
      const sim::Triangle& tri = F[f];
      for (sim::Index v : tri)
        if (v < 0 || std::size_t(v) >= nv)
          throw InputError(
              fmt::format("silhouette: triangle {} references vertex {} (mesh has {} vertex slots)", f, v, nv));
      if (fix_ok[std::size_t(tri[0])] && fix_ok[std::size_t(tri[1])] && fix_ok[std::size_t(tri[2])])
        setup_triangle(fix[std::size_t(tri[0])], fix[std::size_t(tri[1])], fix[std::size_t(tri[2])], cull, gw, gh,
                       tris);
      else
        any_slow = true;
    }
    if (!any_slow) return;
    // Slow path: triangles reaching beyond the guard band or behind a pinhole camera.
    std::vector<Hom> hom;
    project_vertices(P, nv, &hom);
    for (std::size_t f = 0; f < nt; ++f) {
      if (alive && !alive[f]) continue;
      const sim::Triangle& tri = F[f];
      const auto a = std::size_t(tri[0]), b = std::size_t(tri[1]), c = std::size_t(tri[2]);
      if (fix_ok[a] && fix_ok[b] && fix_ok[c]) continue;
      Hom poly[16] = {hom[a], hom[b], hom[c]};
      bool finite = true;
      for (int i = 0; i < 3; ++i)
        finite = finite && std::isfinite(poly[i].x) && std::isfinite(poly[i].y) && std::isfinite(poly[i].w);
      if (!finite) continue;  // a non-finite vertex: nothing sensible to draw
      const int n = clip_polygon(poly, 3, std::holds_alternative<Pinhole>(camera) ? kNearZ : -1.0);
      if (n < 3) continue;
      Fix pts[16];
      for (int i = 0; i < n; ++i) pts[i] = Fix{snap(poly[i].x / poly[i].w), snap(poly[i].y / poly[i].w)};
      for (int i = 1; i + 1 < n; ++i) setup_triangle(pts[0], pts[i], pts[i + 1], cull, gw, gh, tris);
    }
  }

  // Step 3: bins triangles into bands of `band_rows` grid rows.
  void bin(i32 band_rows, i32 nbands) {
    band_offset.assign(std::size_t(nbands) + 1, 0);
    for (const Tri& t : tris)
      for (i32 b = t.r0 / band_rows; b <= (t.r1 - 1) / band_rows; ++b) ++band_offset[std::size_t(b) + 1];
    for (i32 b = 0; b < nbands; ++b) band_offset[std::size_t(b) + 1] += band_offset[std::size_t(b)];
    band_items.resize(std::size_t(band_offset.back()));
    std::vector<i32> cursor(band_offset.begin(), band_offset.end() - 1);
    for (std::size_t i = 0; i < tris.size(); ++i) {
      const Tri& t = tris[i];
      for (i32 b = t.r0 / band_rows; b <= (t.r1 - 1) / band_rows; ++b)
        band_items[std::size_t(cursor[std::size_t(b)]++)] = i32(i);
    }
  }

  template <class Body>
  void for_bands(i32 nbands, Body&& body) {
    if (options.parallel && nbands > 1) {
      tbb::parallel_for(tbb::blocked_range<i32>(0, nbands, 1), [&](const tbb::blocked_range<i32>& r) {
        for (i32 b = r.begin(); b < r.end(); ++b) body(b);
      });
    } else {
      for (i32 b = 0; b < nbands; ++b) body(b);
    }
  }

  // Binary mask of the canvas grid (k = 1) into `mask` (canvas_h x canvas_w CV_8UC1).
  void fill_binary(cv::Mat& mask) {
    const i32 nbands = (canvas_h + kBinaryBandRows - 1) / kBinaryBandRows;
    bin(kBinaryBandRows, nbands);
    const i32 gw = canvas_w;
    for_bands(nbands, [&](i32 b) {
      const i32 ra = b * kBinaryBandRows, rb = std::min(canvas_h, ra + kBinaryBandRows);
      if (mask.isContinuous()) {
        std::memset(mask.ptr<std::uint8_t>(ra), 0, std::size_t(rb - ra) * std::size_t(gw));
      } else {
        for (i32 r = ra; r < rb; ++r) std::memset(mask.ptr<std::uint8_t>(r), 0, std::size_t(gw));
      }
      for (i32 j = band_offset[std::size_t(b)]; j < band_offset[std::size_t(b) + 1]; ++j) {
        raster(tris[std::size_t(band_items[std::size_t(j)])], ra, rb, gw,
               [&](i32 r, i32 x0, i32 x1) { std::memset(mask.ptr<std::uint8_t>(r) + x0, 255, std::size_t(x1 - x0)); });
      }
    });
  }

  // Coverage of the canvas (CV_32FC1 canvas_h x canvas_w) with k x k samples per pixel.
  void fill_coverage(cv::Mat& cov) {
    const i32 k = options.supersample;
    const i32 band_rows = kCoverageBandRows * k;  // grid rows per band
    const i32 gw = canvas_w * k;
    const i32 nbands = (canvas_h + kCoverageBandRows - 1) / kCoverageBandRows;
    bin(band_rows, nbands);
    const float inv = 1.0f / float(k * k);
    for_bands(nbands, [&](i32 b) {
      Scratch& s = scratch.local();
      if (s.buffer.size() != std::size_t(band_rows) * std::size_t(gw)) {
        s.buffer.assign(std::size_t(band_rows) * std::size_t(gw), 0);
        s.lo.assign(std::size_t(band_rows), gw);
        s.hi.assign(std::size_t(band_rows), 0);
      }
      const i32 ra = b * band_rows, rb = std::min(canvas_h * k, ra + band_rows);
      for (i32 j = band_offset[std::size_t(b)]; j < band_offset[std::size_t(b) + 1]; ++j) {
        raster(tris[std::size_t(band_items[std::size_t(j)])], ra, rb, gw, [&](i32 r, i32 x0, i32 x1) {
          const auto rr = std::size_t(r - ra);
          std::memset(s.buffer.data() + rr * std::size_t(gw) + std::size_t(x0), 1, std::size_t(x1 - x0));
          s.lo[rr] = std::min(s.lo[rr], x0);
          s.hi[rr] = std::max(s.hi[rr], x1);
        });
      }
      // Reduce k x k samples per pixel; clear only what was touched.
      const i32 out_r0 = b * kCoverageBandRows, out_r1 = std::min(canvas_h, out_r0 + kCoverageBandRows);
      for (i32 orow = out_r0; orow < out_r1; ++orow) {
        float* o = cov.ptr<float>(orow);
        std::fill(o, o + canvas_w, 0.0f);
        i32 plo = canvas_w, phi = 0;
        for (i32 sr = 0; sr < k; ++sr) {
          const auto rr = std::size_t((orow - out_r0) * k + sr);
          if (s.lo[rr] >= s.hi[rr]) continue;
          const i32 p0 = s.lo[rr] / k, p1 = (s.hi[rr] - 1) / k + 1;
          plo = std::min(plo, p0);
          phi = std::max(phi, p1);
          std::uint8_t* row = s.buffer.data() + rr * std::size_t(gw);
          add_sample_counts(row, k, p0, p1, o);
          std::memset(row + s.lo[rr], 0, std::size_t(s.hi[rr] - s.lo[rr]));
          s.lo[rr] = gw;
          s.hi[rr] = 0;
        }
        for (i32 p = plo; p < phi; ++p) o[p] *= inv;
      }
    });
  }

  template <class Real>
  void render(const sim::Vec3<Real>* P, std::size_t nv, const sim::Triangle* F, const std::uint8_t* alive,
              std::size_t nt, cv::Mat& out) {
    setup(P, nv, F, alive, nt);
    const bool binary = options.supersample == 1;
    const int type = binary ? CV_8UC1 : CV_32FC1;
    out.create(height, width, type);
    if (!distorted) {
      if (binary)
        fill_binary(out);
      else
        fill_coverage(out);
      return;
    }
    if (binary) {
      canvas8.create(canvas_h, canvas_w, CV_8UC1);
      fill_binary(canvas8);
      cv::remap(canvas8, out, map_nearest, cv::noArray(), cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
    } else {
      canvas32.create(canvas_h, canvas_w, CV_32FC1);
      fill_coverage(canvas32);
      cv::remap(canvas32, out, map_linear1, map_linear2, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    }
  }
};

SilhouetteRenderer::SilhouetteRenderer(Camera camera, SilhouetteOptions options)
    : impl_(std::make_unique<Impl>(std::move(camera), options)) {}
SilhouetteRenderer::~SilhouetteRenderer() = default;
SilhouetteRenderer::SilhouetteRenderer(SilhouetteRenderer&&) noexcept = default;
SilhouetteRenderer& SilhouetteRenderer::operator=(SilhouetteRenderer&&) noexcept = default;

const Camera& SilhouetteRenderer::camera() const { return impl_->camera; }
const SilhouetteOptions& SilhouetteRenderer::options() const { return impl_->options; }

template <class Real>
void SilhouetteRenderer::render(const sim::TriMesh<Real>& mesh, cv::Mat& out) {
  if (mesh.triangle_alive.size() != mesh.triangle.size())
    throw InputError(fmt::format("silhouette: mesh has {} triangles but {} triangle flags", mesh.triangle.size(),
                                 mesh.triangle_alive.size()));
  const std::vector<sim::Vec3<Real>> P = mesh.position.to_vectors();  // the mesh stores x, y, z columns
  impl_->render(P.data(), P.size(), mesh.triangle.data(), mesh.triangle_alive.data(), mesh.triangle.size(), out);
}

void SilhouetteRenderer::render(const sim::IndexedMesh& mesh, cv::Mat& out) {
  impl_->render(mesh.V.data(), mesh.V.size(), mesh.F.data(), nullptr, mesh.F.size(), out);
}

template void SilhouetteRenderer::render<float>(const sim::TriMesh<float>&, cv::Mat&);
template void SilhouetteRenderer::render<double>(const sim::TriMesh<double>&, cv::Mat&);

namespace {

// The mask of any mesh SilhouetteRenderer::render takes, at one sample per pixel.
template <class Mesh>
cv::Mat one_sample_mask(const Mesh& mesh, const Camera& camera, SilhouetteOptions o) {
  o.supersample = 1;
  SilhouetteRenderer r(camera, o);
  cv::Mat out;
  r.render(mesh, out);
  return out;
}

}  // namespace

template <class Real>
cv::Mat silhouette_mask(const sim::TriMesh<Real>& mesh, const Camera& camera, const SilhouetteOptions& options) {
  return one_sample_mask(mesh, camera, options);
}

cv::Mat silhouette_mask(const sim::IndexedMesh& mesh, const Camera& camera, const SilhouetteOptions& options) {
  return one_sample_mask(mesh, camera, options);
}

template <class Real>
cv::Mat silhouette_coverage(const sim::TriMesh<Real>& mesh, const Camera& camera, const SilhouetteOptions& options) {
  SilhouetteRenderer r(camera, options);
  cv::Mat out;
  r.render(mesh, out);
  if (out.type() == CV_8UC1) out.convertTo(out, CV_32FC1, 1.0 / 255.0);
  return out;
}

template cv::Mat silhouette_mask<float>(const sim::TriMesh<float>&, const Camera&, const SilhouetteOptions&);
template cv::Mat silhouette_mask<double>(const sim::TriMesh<double>&, const Camera&, const SilhouetteOptions&);
template cv::Mat silhouette_coverage<float>(const sim::TriMesh<float>&, const Camera&, const SilhouetteOptions&);
template cv::Mat silhouette_coverage<double>(const sim::TriMesh<double>&, const Camera&, const SilhouetteOptions&);

}  // namespace meltlab::render
