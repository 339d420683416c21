// Regions from images (marching squares), from binary masks (pixel squares), and back to
// masks (exact pixel-centre scanline). See region.h for the conventions.
//
// Both constructors share one core. The image is thresholded into a 0/1 "inside" buffer
// padded by one outside pixel on every side; a cell is a 2x2 block of pixel centres, and
// only cells whose corners straddle the level are visited (8 cells per 64-bit compare in
// uniform areas). Every visited cell emits oriented segments from a lattice edge where the
// counter-clockwise walk around the cell goes inside -> outside to an edge where it goes
// outside -> inside, so the inside lies on the segment's left (positive shoelace area for
// outer loops, negative for holes). Every crossing edge is the start of exactly one segment
// and the end of exactly one (its two cells walk it in opposite directions), so the
// segments chain into closed loops.
//  - region_from_image places each vertex on its crossing edge by linear interpolation.
//  - region_from_mask places each vertex at the centre of the cell the chain passes
//    through, i.e. at a pixel corner: the chain of cells is exactly the boundary of the
//    union of pixel squares (4-connected foreground at saddles), so its area is the pixel
//    count; collinear steps are then merged.

#include <meltlab/verify/region.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace meltlab::verify {

double loop_area(const std::vector<Vec2d>& loop) {
  const std::size_t n = loop.size();
  if (n < 3) return 0.0;
  // Shoelace relative to the first vertex (reduces cancellation for loops far from 0).
  const Vec2d o = loop[0];
  double twice = 0.0;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const Vec2d a = loop[i] - o, b = loop[i + 1] - o;
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * twice;
}

double region_area(const Region& region) {
  double area = 0.0;
  for (const Polygon& p : region) {
    area += std::abs(loop_area(p.outer));
    for (const auto& h : p.holes) area -= std::abs(loop_area(h));
  }
  return area;
}

std::size_t region_vertex_count(const Region& region) {
  std::size_t n = 0;
  for (const Polygon& p : region) {
    n += p.outer.size();
    for (const auto& h : p.holes) n += h.size();
  }
  return n;
}

namespace {

struct Segment {
  std::uint64_t from, to;  // edge ids
  std::uint32_t cx, cy;    // cell (padded coordinates)
};

// Padded inside-flags: (H+2) rows of (W+2) bytes, plus slack for 8-byte loads.
struct Flags {
  int W = 0, H = 0, Wp = 0, Hp = 0;
  std::vector<std::uint8_t> b;
  const std::uint8_t* row(int y) const { return b.data() + static_cast<std::size_t>(y) * Wp; }
  std::uint8_t at(int x, int y) const { return b[static_cast<std::size_t>(y) * Wp + x]; }
};

Flags make_flags(int W, int H) {
  Flags f;
  f.W = W;
  f.H = H;
  f.Wp = W + 2;
  f.Hp = H + 2;
  f.b.assign(static_cast<std::size_t>(f.Wp) * f.Hp + 16, 0);
  return f;
}

template <typename T, typename Pred>
void fill_flags(Flags& f, const cv::Mat& m, Pred inside) {
  for (int y = 0; y < f.H; ++y) {
    const T* src = m.ptr<T>(y);
    std::uint8_t* dst = f.b.data() + static_cast<std::size_t>(y + 1) * f.Wp + 1;
    for (int x = 0; x < f.W; ++x) dst[x] = inside(src[x]) ? 1 : 0;
  }
}

inline std::uint64_t hedge(const Flags& f, int x, int y) {  // (x,y)-(x+1,y)
  return 2 * (static_cast<std::uint64_t>(y) * f.Wp + static_cast<std::uint64_t>(x));
}
inline std::uint64_t vedge(const Flags& f, int x, int y) {  // (x,y)-(x,y+1)
  return 2 * (static_cast<std::uint64_t>(y) * f.Wp + static_cast<std::uint64_t>(x)) + 1;
}

// Emits the segments of every straddling cell. saddle_connected(x, y) decides whether the
// two inside corners of a saddle cell are joined through the cell.
template <typename SaddleFn>
std::vector<Segment> march(const Flags& f, SaddleFn saddle_connected) {
  std::vector<Segment> segs;
  constexpr std::uint64_t kOnes = 0x0101010101010101ULL;
  auto do_cell = [&](int x, int y) {
    const std::uint8_t* r0 = f.row(y);
    const std::uint8_t* r1 = f.row(y + 1);
    const bool in[4] = {r0[x] != 0, r0[x + 1] != 0, r1[x + 1] != 0, r1[x] != 0};
    if (in[0] == in[1] && in[1] == in[2] && in[2] == in[3]) return;
    const std::uint64_t e[4] = {hedge(f, x, y), vedge(f, x + 1, y), hedge(f, x, y + 1), vedge(f, x, y)};
    const bool saddle = in[0] == in[2] && in[1] == in[3];
    const bool connected = saddle && saddle_connected(x, y);
    for (int k = 0; k < 4; ++k) {
      if (!(in[k] && !in[(k + 1) & 3])) continue;  // not an inside -> outside edge
      int t;
      if (saddle) {
        t = connected ? (k + 1) & 3 : (k + 3) & 3;
      } else {
        t = -1;
        for (int j = 0; j < 4; ++j)
          if (!in[j] && in[(j + 1) & 3]) t = j;
      }
      segs.push_back({e[k], e[t], static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y)});
    }
  };
  const int ncx = f.W + 1;  // cells x in [0, W], y in [0, H]
  for (int y = 0; y <= f.H; ++y) {
    const std::uint8_t* r0 = f.row(y);
    const std::uint8_t* r1 = f.row(y + 1);
    int x = 0;
    for (; x + 8 < f.Wp; x += 8) {
      std::uint64_t w0, w1;
      std::memcpy(&w0, r0 + x, 8);
      std::memcpy(&w1, r1 + x, 8);
      if (w0 == w1 && r0[x + 8] == r1[x + 8]) {
        if ((w0 == 0 && r0[x + 8] == 0) || (w0 == kOnes && r0[x + 8] == 1)) continue;
      }
      for (int i = x; i < x + 8 && i < ncx; ++i) do_cell(i, y);
    }
    for (; x < ncx; ++x) do_cell(x, y);
  }
  return segs;
}

// Chains segments into loops; vertex(seg) gives the vertex emitted for a segment. march()
// emits segments row by row in increasing x, so the successor of a segment — in the cell
// across its end edge — is found by a binary search within that cell row (a handful of
// segments per row for a blob): no sort, no table the size of the image.
template <typename VertexFn>
std::vector<std::vector<Vec2d>> chain(const Flags& f, const std::vector<Segment>& segs, VertexFn vertex) {
  std::vector<std::uint32_t> row_start(static_cast<std::size_t>(f.H) + 2, 0);
  for (const Segment& s : segs) ++row_start[s.cy + 1];
  for (std::size_t y = 1; y < row_start.size(); ++y) row_start[y] += row_start[y - 1];
  auto successor = [&](const Segment& s) -> std::size_t {
    const std::uint64_t lin = s.to >> 1;
    const auto ex = static_cast<std::uint32_t>(lin % static_cast<std::uint64_t>(f.Wp));
    const auto ey = static_cast<std::uint32_t>(lin / static_cast<std::uint64_t>(f.Wp));
    std::uint32_t nx = ex, ny = ey;  // the cell on the far side of the edge
    if (s.to & 1) {                  // vertical edge: cells (ex - 1, ey) and (ex, ey)
      if (nx == s.cx) --nx;
    } else {  // horizontal edge: cells (ex, ey - 1) and (ex, ey)
      if (ny == s.cy) --ny;
    }
    auto first = segs.begin() + row_start[ny], last = segs.begin() + row_start[ny + 1];
    auto it = std::lower_bound(first, last, nx, [](const Segment& g, std::uint32_t x) { return g.cx < x; });
    for (; it != last && it->cx == nx; ++it)
      if (it->from == s.to) return static_cast<std::size_t>(it - segs.begin());
    throw std::logic_error("region: open marching-squares chain");
  };
  std::vector<std::uint8_t> used(segs.size(), 0);
  std::vector<std::vector<Vec2d>> loops;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    if (used[i]) continue;
    std::vector<Vec2d> loop;
    std::size_t cur = i;
    while (!used[cur]) {
      used[cur] = 1;
      loop.push_back(vertex(segs[cur]));
      cur = successor(segs[cur]);
    }
    loops.push_back(std::move(loop));
  }
  return loops;
}

// Removes consecutive duplicates (cyclically); optionally merges collinear runs of
// axis-aligned steps (exact for lattice points).
void clean_loop(std::vector<Vec2d>& loop, bool merge_collinear) {
  std::vector<Vec2d> out;
  out.reserve(loop.size());
  for (const Vec2d& p : loop)
    if (out.empty() || out.back() != p) out.push_back(p);
  while (out.size() > 1 && out.back() == out.front()) out.pop_back();
  if (merge_collinear && out.size() >= 3) {
    auto collinear = [](const Vec2d& a, const Vec2d& b, const Vec2d& c) {
      return (b.x() - a.x()) * (c.y() - b.y()) - (b.y() - a.y()) * (c.x() - b.x()) == 0.0;
    };
    std::vector<Vec2d> m;
    m.reserve(out.size());
    const std::size_t n = out.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2d& prev = out[(i + n - 1) % n];
      const Vec2d& next = out[(i + 1) % n];
      if (!collinear(prev, out[i], next)) m.push_back(out[i]);
    }
    out.swap(m);
  }
  loop.swap(out);
}

// Splits loops into outers (positive area) and holes (negative area) and gives every hole
// its polygon. Loops do not cross (they may touch at vertices). Each hole is probed along a
// row v = c that crosses it (an integer row when it has one: marching-squares loops always
// enclose a pixel centre). All crossings of all loops with that row are sorted; the material
// just left of the hole's leftmost crossing belongs to the hole's polygon, so the crossing
// before it bounds the same face: the polygon's outer loop, or another hole of it. Holes
// and loops so linked are merged (union-find); each set holds the one outer of its face.
// Edges are bucketed by unit bands of v, so a row costs O(edges in one band log): fast
// even for thousands of speckles.
Region nest(std::vector<std::vector<Vec2d>>&& loops) {
  const std::size_t n = loops.size();
  std::vector<double> area(n, 0.0);
  double ymin = std::numeric_limits<double>::infinity(), ymax = -ymin;
  std::vector<std::pair<double, std::size_t>> probes;  // (row c, hole)
  for (std::size_t i = 0; i < n; ++i) {
    if (loops[i].size() >= 3) area[i] = loop_area(loops[i]);
    if (area[i] == 0) continue;
    double lo = loops[i][0].y(), hi = lo;
    for (const Vec2d& p : loops[i]) {
      lo = std::min(lo, p.y());
      hi = std::max(hi, p.y());
    }
    ymin = std::min(ymin, lo);
    ymax = std::max(ymax, hi);
    if (area[i] < 0) {
      const double j = std::ceil(lo);
      probes.emplace_back(j < hi ? j : 0.5 * (lo + hi), i);
    }
  }
  std::vector<std::size_t> uf(n);
  for (std::size_t i = 0; i < n; ++i) uf[i] = i;
  auto find = [&](std::size_t i) {
    while (uf[i] != i) i = uf[i] = uf[uf[i]];
    return i;
  };
  if (!probes.empty()) {
    std::sort(probes.begin(), probes.end());
    // Bands [k, k+1) of v, k = floor(v) - k0; CSR lists of (loop, edge) per band, only for
    // the bands that hold probe rows.
    const double k0 = std::floor(ymin);
    const auto nb = static_cast<std::size_t>(std::floor(ymax) - k0) + 1;
    std::vector<std::uint8_t> wanted(nb, 0);
    for (const auto& pr : probes) wanted[static_cast<std::size_t>(std::floor(pr.first) - k0)] = 1;
    std::vector<std::uint32_t> start(nb + 1, 0);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> items;
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::uint32_t> fill;
      if (pass == 1) {
        for (std::size_t k = 1; k <= nb; ++k) start[k] += start[k - 1];
        items.resize(start[nb]);
        fill.assign(start.begin(), start.end() - 1);
      }
      for (std::size_t li = 0; li < n; ++li) {
        if (area[li] == 0) continue;
        const auto& l = loops[li];
        for (std::size_t e = 0; e < l.size(); ++e) {
          const Vec2d& a = l[e];
          const Vec2d& b = l[(e + 1) % l.size()];
          if (a.y() == b.y()) continue;
          const auto k_lo = static_cast<std::size_t>(std::floor(std::min(a.y(), b.y())) - k0);
          const auto k_hi = static_cast<std::size_t>(std::floor(std::max(a.y(), b.y())) - k0);
          for (std::size_t k = k_lo; k <= k_hi; ++k) {
            if (!wanted[k]) continue;
            if (pass == 0)
              ++start[k + 1];
            else
              items[fill[k]++] = {static_cast<std::uint32_t>(li), static_cast<std::uint32_t>(e)};
          }
        }
      }
    }
    std::vector<std::pair<double, std::size_t>> xs;  // (x, loop) crossings of one row
    for (std::size_t g = 0; g < probes.size();) {
      const double c = probes[g].first;
      const auto k = static_cast<std::size_t>(std::floor(c) - k0);
      xs.clear();
      for (std::uint32_t it = start[k]; it < start[k + 1]; ++it) {
        const auto [li, e] = items[it];
        const auto& l = loops[li];
        const Vec2d& a = l[e];
        const Vec2d& b = l[(e + 1) % l.size()];
        if ((a.y() > c) == (b.y() > c)) continue;  // half-open crossing rule
        xs.emplace_back(a.x() + (c - a.y()) * (b.x() - a.x()) / (b.y() - a.y()), li);
      }
      std::sort(xs.begin(), xs.end());
      for (; g < probes.size() && probes[g].first == c; ++g) {
        const std::size_t h = probes[g].second;
        std::size_t i = 0;
        while (i < xs.size() && xs[i].second != h) ++i;
        if (i > 0 && i < xs.size()) uf[find(h)] = find(xs[i - 1].second);
      }
    }
  }
  // Polygon per set: its outer loop (a set without one — impossible for loops that do not
  // cross — loses its holes).
  Region region;
  std::vector<int> poly_of(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    if (area[i] <= 0) continue;
    const std::size_t r = find(i);
    if (poly_of[r] >= 0) {  // two outers linked (touching loops): keep them apart
      region.push_back(Polygon{std::move(loops[i]), {}});
      continue;
    }
    poly_of[r] = static_cast<int>(region.size());
    region.push_back(Polygon{std::move(loops[i]), {}});
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (area[i] >= 0) continue;
    const int p = poly_of[find(i)];
    if (p >= 0) region[static_cast<std::size_t>(p)].holes.push_back(std::move(loops[i]));
  }
  return region;
}

template <typename T>
Region march_image(const cv::Mat& img, double iso) {
  const int W = img.cols, H = img.rows;
  Flags f = make_flags(W, H);
  if constexpr (std::is_same_v<T, std::uint8_t>) {
    // v > iso for integer v <=> v >= floor(iso) + 1 (an integer compare that vectorises).
    const double th = std::floor(iso) + 1.0;
    if (th <= 0) {
      fill_flags<T>(f, img, [](T) { return true; });
    } else if (th > 255) {
      // nothing inside
    } else {
      const auto t8 = static_cast<std::uint8_t>(th);
      fill_flags<T>(f, img, [t8](T v) { return v >= t8; });
    }
  } else if constexpr (std::is_same_v<T, float>) {
    // For float v: v > iso <=> v > fi with fi the largest float <= iso (a float compare
    // that vectorises twice as wide as the double one).
    float fi = static_cast<float>(iso);
    if (static_cast<double>(fi) > iso) fi = std::nextafter(fi, -std::numeric_limits<float>::infinity());
    fill_flags<T>(f, img, [fi](T v) { return v > fi; });
  } else {
    fill_flags<T>(f, img, [iso](T v) { return v > iso; });
  }
  // Pixels outside the image (and NaN pixels) read as `pad`: 0, the natural background of
  // coverage, probability and intensity images, when that is outside (iso > 0); else
  // iso - 1.
  const double pad = iso > 0 ? 0.0 : iso - 1.0;
  auto value = [&](int px, int py) -> double {  // padded coordinates
    const int x = px - 1, y = py - 1;
    if (x < 0 || y < 0 || x >= W || y >= H) return pad;
    const double v = static_cast<double>(img.ptr<T>(y)[x]);
    return std::isnan(v) ? pad : v;
  };
  auto saddle = [&](int x, int y) {
    const double m = 0.25 * (value(x, y) + value(x + 1, y) + value(x + 1, y + 1) + value(x, y + 1));
    return m > iso;
  };
  std::vector<Segment> segs = march(f, saddle);
  auto vertex = [&](const Segment& s) -> Vec2d {
    const std::uint64_t id = s.from;
    const bool vertical = (id & 1) != 0;
    const std::uint64_t lin = id >> 1;
    const int x = static_cast<int>(lin % static_cast<std::uint64_t>(f.Wp));
    const int y = static_cast<int>(lin / static_cast<std::uint64_t>(f.Wp));
    const double fa = value(x, y);
    const double fb = vertical ? value(x, y + 1) : value(x + 1, y);
    double t = (iso - fa) / (fb - fa);
    if (!(t >= 0.0)) t = std::isnan(t) ? 0.5 : 0.0;  // +-inf pixels
    if (t > 1.0) t = 1.0;
    return vertical ? Vec2d(x - 1.0, y - 1.0 + t) : Vec2d(x - 1.0 + t, y - 1.0);
  };
  std::vector<std::vector<Vec2d>> loops = chain(f, segs, vertex);
  for (auto& l : loops) clean_loop(l, false);
  return nest(std::move(loops));
}

}  // namespace

Region region_from_image(const cv::Mat& image, double iso) {
  if (!std::isfinite(iso)) throw std::invalid_argument("region_from_image: iso level must be finite");
  if (image.empty()) return {};
  switch (image.type()) {
    case CV_8UC1:
      return march_image<std::uint8_t>(image, iso);
    case CV_32FC1:
      return march_image<float>(image, iso);
    case CV_64FC1:
      return march_image<double>(image, iso);
    default:
      throw std::invalid_argument("region_from_image: image must be CV_8UC1, CV_32FC1 or CV_64FC1 (got type " +
                                  std::to_string(image.type()) + ")");
  }
}

Region region_from_mask(const cv::Mat& mask) {
  if (mask.empty()) return {};
  if (mask.channels() != 1) throw std::invalid_argument("region_from_mask: mask must have one channel");
  cv::Mat m8;
  if (mask.type() == CV_8UC1) {
    m8 = mask;
  } else {
    cv::compare(mask, 0, m8, cv::CMP_NE);
  }
  Flags f = make_flags(m8.cols, m8.rows);
  fill_flags<std::uint8_t>(f, m8, [](std::uint8_t v) { return v != 0; });
  // Saddles keep the inside corners apart (4-connected foreground); the two loops then
  // touch at the shared pixel corner.
  std::vector<Segment> segs = march(f, [](int, int) { return false; });
  // The cell with padded corner (x, y) is centred at padded (x + 0.5, y + 0.5), i.e. the
  // pixel corner (x - 0.5, y - 0.5).
  auto vertex = [](const Segment& s) { return Vec2d(s.cx - 0.5, s.cy - 0.5); };
  std::vector<std::vector<Vec2d>> loops = chain(f, segs, vertex);
  for (auto& l : loops) clean_loop(l, true);
  return nest(std::move(loops));
}

cv::Mat rasterize_region(const Region& region, int width, int height) {
  if (width < 0 || height < 0) throw std::invalid_argument("rasterize_region: negative image size");
  cv::Mat out(height, width, CV_8UC1, cv::Scalar(0));
  if (width == 0 || height == 0) return out;
  // Crossings of every loop edge with the pixel-centre rows v = j. An edge crosses row j
  // iff (a.v > j) != (b.v > j) (half-open in v); pixel i is inside iff an odd number of
  // crossings lie at u < i (half-open in u). The crossing abscissa is the exact line/row
  // intersection in double precision, so a pixel centre is misclassified only if it lies
  // within rounding (~1e-16 relative) of the boundary — unlike cv::fillPoly, which rounds
  // the vertices to a 2^-shift grid and fills by its own edge rules.
  std::vector<std::pair<int, double>> xs;
  auto add_loop = [&](const std::vector<Vec2d>& l) {
    const std::size_t n = l.size();
    if (n < 2) return;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2d& a = l[i];
      const Vec2d& b = l[(i + 1) % n];
      if (a.y() == b.y()) continue;
      const double lo = std::min(a.y(), b.y()), hi = std::max(a.y(), b.y());
      // rows j with lo <= j < hi
      double j0 = std::ceil(lo), j1 = std::ceil(hi) - 1.0;
      j0 = std::max(j0, 0.0);
      j1 = std::min(j1, static_cast<double>(height - 1));
      for (double j = j0; j <= j1; j += 1.0) {
        const double x = a.x() + (j - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
        xs.emplace_back(static_cast<int>(j), x);
      }
    }
  };
  for (const Polygon& p : region) {
    add_loop(p.outer);
    for (const auto& h : p.holes) add_loop(h);
  }
  std::sort(xs.begin(), xs.end());
  for (std::size_t k = 0; k + 1 < xs.size();) {
    const int j = xs[k].first;
    if (xs[k + 1].first != j) {  // odd count on a row (cannot happen for closed loops)
      ++k;
      continue;
    }
    // span: pixels i with x0 < i <= x1
    const double x0 = xs[k].second, x1 = xs[k + 1].second;
    const double lo = std::max(std::floor(x0) + 1.0, 0.0);
    const double hi = std::min(std::floor(x1), static_cast<double>(width - 1));
    if (lo <= hi) {
      std::uint8_t* row = out.ptr<std::uint8_t>(j);
      std::memset(row + static_cast<int>(lo), 255, static_cast<std::size_t>(hi - lo) + 1);
    }
    k += 2;
  }
  return out;
}

}  // namespace meltlab::verify
