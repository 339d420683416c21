// The P measure (Eq. 8.1) on pixel masks and coverage images, and boundary distances.
// compare_regions_exact lives in src/cgal/exact_area.cpp (CGAL, exact arithmetic).

#include <meltlab/verify/metrics.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

namespace meltlab::verify {

namespace {

AreaComparison make_comparison(double s_a, double s_b, double s_i) {
  AreaComparison c;
  c.S_A = s_a;
  c.S_B = s_b;
  c.S_I = s_i;
  const double uni = s_a + s_i + s_b;
  if (uni > 0) {
    c.P = (s_a + s_b) / uni;
    c.IoU = s_i / uni;
    c.Dice = 2 * s_i / (2 * s_i + s_a + s_b);
  } else {  // both empty: identical contours
    c.P = 0;
    c.IoU = 1;
    c.Dice = 1;
  }
  return c;
}

std::string size_str(const cv::Mat& m) {
  return std::to_string(m.cols) + "x" + std::to_string(m.rows) + " type " + std::to_string(m.type());
}

void check_pair(const char* what, const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type())
    throw std::invalid_argument(std::string(what) + ": images differ in size or type (" + size_str(a) + " vs " +
                                size_str(b) + ")");
  if (a.channels() != 1) throw std::invalid_argument(std::string(what) + ": images must have one channel");
}

}  // namespace

AreaComparison compare_masks(const cv::Mat& photo, const cv::Mat& render) {
  check_pair("compare_masks", photo, render);
  cv::Mat a = photo, b = render;
  if (a.type() != CV_8UC1) {
    cv::compare(photo, 0, a, cv::CMP_NE);
    cv::compare(render, 0, b, cv::CMP_NE);
  }
  // One pass: counts of a, b and a&b (per-row 32-bit counters vectorise).
  std::uint64_t na = 0, nb = 0, ni = 0;
  for (int y = 0; y < a.rows; ++y) {
    const std::uint8_t* pa = a.ptr<std::uint8_t>(y);
    const std::uint8_t* pb = b.ptr<std::uint8_t>(y);
    std::uint32_t ra = 0, rb = 0, ri = 0;
    for (int x = 0; x < a.cols; ++x) {
      const std::uint32_t ia = pa[x] != 0, ib = pb[x] != 0;
      ra += ia;
      rb += ib;
      ri += ia & ib;
    }
    na += ra;
    nb += rb;
    ni += ri;
  }
  return make_comparison(static_cast<double>(na - ni), static_cast<double>(nb - ni), static_cast<double>(ni));
}

AreaComparison compare_coverage(const cv::Mat& photo, const cv::Mat& render) {
  check_pair("compare_coverage", photo, render);
  if (photo.type() != CV_32FC1) throw std::invalid_argument("compare_coverage: coverage images must be CV_32FC1");
  double sa = 0, sb = 0, si = 0;
  for (int y = 0; y < photo.rows; ++y) {
    const float* pa = photo.ptr<float>(y);
    const float* pb = render.ptr<float>(y);
    // Four independent double lanes (vectorisable without reassociation flags).
    double la[4] = {0, 0, 0, 0}, lb[4] = {0, 0, 0, 0}, li[4] = {0, 0, 0, 0};
    int x = 0;
    for (; x + 4 <= photo.cols; x += 4) {
      for (int k = 0; k < 4; ++k) {
        const double va = pa[x + k], vb = pb[x + k];
        la[k] += va;
        lb[k] += vb;
        li[k] += std::min(va, vb);
      }
    }
    for (; x < photo.cols; ++x) {
      const double va = pa[x], vb = pb[x];
      la[0] += va;
      lb[0] += vb;
      li[0] += std::min(va, vb);
    }
    sa += (la[0] + la[1]) + (la[2] + la[3]);
    sb += (lb[0] + lb[1]) + (lb[2] + lb[3]);
    si += (li[0] + li[1]) + (li[2] + li[3]);
  }
  return make_comparison(sa - si, sb - si, si);
}

// ---- boundary distances -----------------------------------------------------------------

namespace {

struct Seg {
  Vec2d a, b;
};

void collect_segments(const Region& r, std::vector<Seg>& out) {
  auto add = [&](const std::vector<Vec2d>& l) {
    const std::size_t n = l.size();
    if (n < 2) return;
    for (std::size_t i = 0; i < n; ++i) out.push_back({l[i], l[(i + 1) % n]});
  };
  for (const Polygon& p : r) {
    add(p.outer);
    for (const auto& h : p.holes) add(h);
  }
}

// Samples every segment at (at most) `spacing`: n = ceil(len / spacing) samples at
// t = k / n, k < n (the vertices are samples).
std::vector<Vec2d> sample(const std::vector<Seg>& segs, double spacing) {
  std::vector<Vec2d> s;
  for (const Seg& g : segs) {
    const double len = (g.b - g.a).norm();
    const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil(len / spacing)));
    for (std::size_t k = 0; k < n; ++k)
      s.push_back(g.a + (g.b - g.a) * (static_cast<double>(k) / static_cast<double>(n)));
  }
  return s;
}

double point_segment_d2(const Vec2d& p, const Seg& g) {
  const Vec2d d = g.b - g.a;
  const double dd = d.squaredNorm();
  double t = dd > 0 ? (p - g.a).dot(d) / dd : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return (g.a + t * d - p).squaredNorm();
}

// Uniform grid of segments (each in every cell its bounding box overlaps) with a ring
// search for the nearest segment: O(1) segments per query for boundary-like inputs.
class SegmentGrid {
 public:
  explicit SegmentGrid(const std::vector<Seg>& segs) : segs_(segs) {
    lo_ = hi_ = segs[0].a;
    double total = 0;
    for (const Seg& g : segs) {
      lo_ = lo_.cwiseMin(g.a).cwiseMin(g.b);
      hi_ = hi_.cwiseMax(g.a).cwiseMax(g.b);
      total += (g.b - g.a).norm();
    }
    const Vec2d ext = (hi_ - lo_).cwiseMax(Vec2d(1e-9, 1e-9));
    const double n = static_cast<double>(segs.size());
    // Cell size: about one mean segment length, at most ~4n cells, at most 4096 per axis.
    h_ = std::max({total / n, std::sqrt(ext.x() * ext.y() / (4 * n)), ext.x() / 4096, ext.y() / 4096, 1e-9});
    nx_ = static_cast<int>(ext.x() / h_) + 1;
    ny_ = static_cast<int>(ext.y() / h_) + 1;
    // Counting sort into CSR buckets.
    start_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::uint32_t> fill;
      if (pass == 1) {
        for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
        items_.resize(start_.back());
        fill.assign(start_.begin(), start_.end() - 1);
      }
      for (std::size_t i = 0; i < segs.size(); ++i) {
        const Seg& g = segs[i];
        const int x0 = cx(std::min(g.a.x(), g.b.x())), x1 = cx(std::max(g.a.x(), g.b.x()));
        const int y0 = cy(std::min(g.a.y(), g.b.y())), y1 = cy(std::max(g.a.y(), g.b.y()));
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) {
            const std::size_t c = static_cast<std::size_t>(y) * nx_ + x;
            if (pass == 0)
              ++start_[c + 1];
            else
              items_[fill[c]++] = static_cast<std::uint32_t>(i);
          }
      }
    }
  }

  double nearest(const Vec2d& p) const {
    const int px = cx(p.x()), py = cy(p.y());
    double best = std::numeric_limits<double>::infinity();
    for (int r = 0;; ++r) {
      const int x0 = px - r, x1 = px + r, y0 = py - r, y1 = py + r;
      for (int y = std::max(y0, 0); y <= std::min(y1, ny_ - 1); ++y) {
        const bool edge_row = (y == y0 || y == y1);
        for (int x = std::max(x0, 0); x <= std::min(x1, nx_ - 1); ++x) {
          if (!edge_row && x != x0 && x != x1) continue;  // interior done in earlier rings
          const std::size_t c = static_cast<std::size_t>(y) * nx_ + x;
          for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k)
            best = std::min(best, point_segment_d2(p, segs_[items_[k]]));
        }
      }
      // Lower bound on the distance to any cell outside the examined block.
      double bound = std::numeric_limits<double>::infinity();
      bool more = false;
      if (x0 > 0) more = true, bound = std::min(bound, std::max(0.0, p.x() - (lo_.x() + x0 * h_)));
      if (x1 < nx_ - 1) more = true, bound = std::min(bound, std::max(0.0, lo_.x() + (x1 + 1) * h_ - p.x()));
      if (y0 > 0) more = true, bound = std::min(bound, std::max(0.0, p.y() - (lo_.y() + y0 * h_)));
      if (y1 < ny_ - 1) more = true, bound = std::min(bound, std::max(0.0, lo_.y() + (y1 + 1) * h_ - p.y()));
      if (!more || best <= bound * bound) break;
    }
    return std::sqrt(best);
  }

 private:
  int cx(double x) const { return std::clamp(static_cast<int>(std::floor((x - lo_.x()) / h_)), 0, nx_ - 1); }
  int cy(double y) const { return std::clamp(static_cast<int>(std::floor((y - lo_.y()) / h_)), 0, ny_ - 1); }

  const std::vector<Seg>& segs_;
  Vec2d lo_, hi_;
  double h_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<std::uint32_t> start_, items_;
};

void directed(const std::vector<Vec2d>& samples, const std::vector<Seg>& target, double& max_d, double& mean_d) {
  const SegmentGrid grid(target);
  double mx = 0, sum = 0;
  for (const Vec2d& p : samples) {
    const double d = grid.nearest(p);
    mx = std::max(mx, d);
    sum += d;
  }
  max_d = mx;
  mean_d = samples.empty() ? 0.0 : sum / static_cast<double>(samples.size());
}

}  // namespace

ContourDistances contour_distances(const Region& photo, const Region& render, double spacing) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw std::invalid_argument("contour_distances: spacing must be positive and finite (got " +
                                std::to_string(spacing) + ")");
  std::vector<Seg> sa, sb;
  collect_segments(photo, sa);
  collect_segments(render, sb);
  ContourDistances d;
  if (sa.empty() && sb.empty()) return d;
  if (sa.empty() || sb.empty()) {
    const double inf = std::numeric_limits<double>::infinity();
    d.hausdorff = d.mean = inf;
    d.photo_to_render_max = d.render_to_photo_max = inf;
    d.photo_to_render_mean = d.render_to_photo_mean = inf;
    return d;
  }
  directed(sample(sa, spacing), sb, d.photo_to_render_max, d.photo_to_render_mean);
  directed(sample(sb, spacing), sa, d.render_to_photo_max, d.render_to_photo_mean);
  d.hausdorff = std::max(d.photo_to_render_max, d.render_to_photo_max);
  d.mean = 0.5 * (d.photo_to_render_mean + d.render_to_photo_mean);
  return d;
}

}  // namespace meltlab::verify
