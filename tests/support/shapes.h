#pragma once
// Shapes with closed-form areas: the verify metrics tests and the P-measure benchmark
// (experiments/bench/bench_p_measure.cpp).

#include <meltlab/verify/region.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <numbers>

namespace meltlab::verify::testing {

inline constexpr double kPi = std::numbers::pi;

/// Regular n-gon inscribed in the circle (cx, cy, r), counter-clockwise (positive area).
inline std::vector<Vec2d> ngon(double cx, double cy, double r, int n, double phase = 0.1234) {
  std::vector<Vec2d> l;
  for (int k = 0; k < n; ++k) {
    const double t = phase + 2 * kPi * k / n;
    l.emplace_back(cx + r * std::cos(t), cy + r * std::sin(t));
  }
  return l;
}
/// Exact area of the inscribed regular n-gon.
inline double ngon_area(double r, int n) { return 0.5 * n * r * r * std::sin(2 * kPi / n); }

inline Region disc_region(double cx, double cy, double r, int n, double phase = 0.1234) {
  return {Polygon{ngon(cx, cy, r, n, phase), {}}};
}

inline std::vector<Vec2d> rect(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};  // CCW as numbers
}
inline std::vector<Vec2d> reversed(std::vector<Vec2d> l) { return {l.rbegin(), l.rend()}; }

/// Lens area of two discs of radius r whose centres are d apart (0 <= d <= 2r).
inline double lens_area(double r, double d) {
  return 2 * r * r * std::acos(d / (2 * r)) - 0.5 * d * std::sqrt(4 * r * r - d * d);
}
/// Eq. 8.1 for two equal discs: (2 pi r^2 - 2 A_I) / (2 pi r^2 - A_I).
inline double disc_pair_P(double r, double d) {
  const double a = kPi * r * r, i = lens_area(r, d);
  return (2 * a - 2 * i) / (2 * a - i);
}

/// Binary disc mask: pixel centre strictly inside the circle.
inline cv::Mat disc_mask(int w, int h, double cx, double cy, double r) {
  cv::Mat m(h, w, CV_8UC1, cv::Scalar(0));
  for (int y = 0; y < h; ++y) {
    auto* row = m.ptr<std::uint8_t>(y);
    const double dy = y - cy;
    if (std::abs(dy) >= r) continue;
    const double half = std::sqrt(r * r - dy * dy);
    for (int x = std::max(0, static_cast<int>(std::floor(cx - half)));
         x <= std::min(w - 1, static_cast<int>(std::ceil(cx + half))); ++x) {
      const double dx = x - cx;
      if (dx * dx + dy * dy < r * r) row[x] = 255;
    }
  }
  return m;
}

/// Disc coverage (CV_32FC1) by s x s supersampling of each pixel square; pixels farther than
/// sqrt(2)/2 from the circle are fully in or out (exact), only the boundary band is sampled.
inline cv::Mat disc_coverage(int w, int h, double cx, double cy, double r, int s) {
  cv::Mat m(h, w, CV_32FC1, cv::Scalar(0));
  const double band = std::sqrt(0.5);
  for (int y = 0; y < h; ++y) {
    auto* row = m.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      const double d = std::hypot(x - cx, y - cy);
      if (d <= r - band) {
        row[x] = 1.0f;
      } else if (d < r + band) {
        int n = 0;
        for (int j = 0; j < s; ++j)
          for (int i = 0; i < s; ++i) {
            const double px = x - 0.5 + (i + 0.5) / s, py = y - 0.5 + (j + 0.5) / s;
            n += (px - cx) * (px - cx) + (py - cy) * (py - cy) < r * r;
          }
        row[x] = static_cast<float>(n) / static_cast<float>(s * s);
      }
    }
  }
  return m;
}

/// Random blobs: thresholded smoothed noise (holes, islands, diagonal pinches).
inline cv::Mat random_blobs(int w, int h, unsigned seed, double sigma, double level = 0.5) {
  cv::RNG rng(seed);
  cv::Mat noise(h, w, CV_32FC1);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::Mat smooth;
  if (sigma > 0)
    cv::GaussianBlur(noise, smooth, cv::Size(0, 0), sigma);
  else
    smooth = noise;
  double lo, hi;
  cv::minMaxLoc(smooth, &lo, &hi);
  cv::Mat m;
  cv::compare(smooth, lo + level * (hi - lo), m, cv::CMP_GT);
  return m;
}

}  // namespace meltlab::verify::testing
