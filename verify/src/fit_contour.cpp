#include "fit_detail.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meltlab::verify::fit_detail {

std::vector<Segment> segments_of(const Region& region) {
  std::vector<Segment> s;
  auto add = [&](const std::vector<Vec2d>& loop) {
    for (std::size_t i = 0; i < loop.size(); ++i) s.push_back({loop[i], loop[(i + 1) % loop.size()]});
  };
  for (const Polygon& p : region) {
    add(p.outer);
    for (const auto& h : p.holes) add(h);
  }
  return s;
}

double point_segment_distance(const Vec2d& p, const Segment& s) {
  const Vec2d d = s.b - s.a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (s.a + t * d - p).norm();
}

/// Even-odd point-in-region over all loops (pixel coordinates).
bool inside(const Vec2d& p, const std::vector<Segment>& segs) {
  bool in = false;
  for (const Segment& s : segs) {
    if ((s.a.y() > p.y()) != (s.b.y() > p.y())) {
      const double x = s.a.x() + (p.y() - s.a.y()) * (s.b.x() - s.a.x()) / (s.b.y() - s.a.y());
      if (x > p.x()) in = !in;
    }
  }
  return in;
}

double signed_distance(const Vec2d& p, const std::vector<Segment>& segs) {
  double d = std::numeric_limits<double>::infinity();
  for (const Segment& s : segs) d = std::min(d, point_segment_distance(p, s));
  return inside(p, segs) ? -d : d;
}

/// `n` points spread evenly (by arc length) over all loops of a region.
std::vector<Vec2d> sample_contour(const std::vector<Segment>& segs, int n) {
  double total = 0;
  for (const Segment& s : segs) total += (s.b - s.a).norm();
  std::vector<Vec2d> out;
  if (total <= 0 || n <= 0) return out;
  const double step = total / n;
  double next = 0.5 * step, run = 0;
  for (const Segment& s : segs) {
    const double len = (s.b - s.a).norm();
    while (next <= run + len && static_cast<int>(out.size()) < n) {
      const double t = len > 0 ? (next - run) / len : 0;
      out.push_back(s.a + t * (s.b - s.a));
      next += step;
    }
    run += len;
  }
  while (static_cast<int>(out.size()) < n) out.push_back(segs.back().b);
  return out;
}

/// Bilinear lookup with clamping at the border.
double bilinear(const cv::Mat& f, const Vec2d& p) {
  const double x = std::clamp(p.x(), 0.0, f.cols - 1.0), y = std::clamp(p.y(), 0.0, f.rows - 1.0);
  const int x0 = std::min(static_cast<int>(x), f.cols - 2 < 0 ? 0 : f.cols - 2);
  const int y0 = std::min(static_cast<int>(y), f.rows - 2 < 0 ? 0 : f.rows - 2);
  const int x1 = std::min(x0 + 1, f.cols - 1), y1 = std::min(y0 + 1, f.rows - 1);
  const double tx = x - x0, ty = y - y0;
  const double a = f.at<float>(y0, x0), b = f.at<float>(y0, x1), c = f.at<float>(y1, x0), d = f.at<float>(y1, x1);
  return (a * (1 - tx) + b * tx) * (1 - ty) + (c * (1 - tx) + d * tx) * ty;
}

/// Signed distance (px) to the boundary of a binary mask, negative inside; the boundary is
/// taken half-way between pixel centres.
cv::Mat signed_distance_image(const cv::Mat& mask) {
  cv::Mat in = mask != 0, out = mask == 0, d_in, d_out;
  cv::distanceTransform(in, d_in, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(out, d_out, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat sdf(mask.size(), CV_32FC1);
  for (int y = 0; y < mask.rows; ++y) {
    const float* di = d_in.ptr<float>(y);
    const float* dout = d_out.ptr<float>(y);
    float* s = sdf.ptr<float>(y);
    for (int x = 0; x < mask.cols; ++x) s[x] = di[x] > 0 ? 0.5F - di[x] : dout[x] - 0.5F;
  }
  return sdf;
}

}  // namespace meltlab::verify::fit_detail
