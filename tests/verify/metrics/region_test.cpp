// Regions: shoelace areas, pixel-square boundaries (exact areas, exact round trip through the
// scanline rasteriser), marching squares (sub-pixel areas, holes, image types).

#include "shapes.h"

#include <meltlab/verify/region.h>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <cmath>
#include <stdexcept>

using namespace meltlab::verify;
using namespace meltlab::verify::testing;

namespace {

bool masks_equal(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  return cv::countNonZero(a != b) == 0;
}

void expect_oriented(const Region& r) {
  for (const Polygon& p : r) {
    EXPECT_GT(loop_area(p.outer), 0.0);
    for (const auto& h : p.holes) EXPECT_LT(loop_area(h), 0.0);
  }
}

}  // namespace

TEST(Region, ShoelaceAreas) {
  const auto sq = rect(1, 2, 4, 6);
  EXPECT_EQ(loop_area(sq), 12.0);
  EXPECT_EQ(loop_area(reversed(sq)), -12.0);
  const Region r{Polygon{sq, {reversed(rect(2, 3, 3, 4))}}};
  EXPECT_EQ(region_area(r), 11.0);
  EXPECT_EQ(region_vertex_count(r), 8u);
  EXPECT_EQ(loop_area({}), 0.0);
}

TEST(RegionFromMask, SinglePixelAndFullImage) {
  cv::Mat m(5, 7, CV_8UC1, cv::Scalar(0));
  m.at<std::uint8_t>(2, 3) = 255;
  Region r = region_from_mask(m);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].outer.size(), 4u);  // collinear steps merged
  EXPECT_EQ(region_area(r), 1.0);
  // pixel (3, 2) is the square [2.5, 3.5] x [1.5, 2.5]
  for (const Vec2d& v : r[0].outer) {
    EXPECT_TRUE(v.x() == 2.5 || v.x() == 3.5);
    EXPECT_TRUE(v.y() == 1.5 || v.y() == 2.5);
  }
  cv::Mat full(5, 7, CV_8UC1, cv::Scalar(1));
  r = region_from_mask(full);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].outer.size(), 4u);
  EXPECT_EQ(region_area(r), 35.0);
  EXPECT_TRUE(masks_equal(rasterize_region(r, 7, 5), full * 255));
  EXPECT_TRUE(region_from_mask(cv::Mat(4, 4, CV_8UC1, cv::Scalar(0))).empty());
}

// Area == pixel count and exact round trip, on many random masks: smooth blobs (holes,
// islands in holes) and raw noise (every kind of diagonal pinch). The vertices are
// half-integers, so shoelace sums are exact in double: equality, not a tolerance.
TEST(RegionFromMask, AreaIsPixelCountAndRoundTripIsExact) {
  int with_holes = 0;
  for (unsigned seed = 0; seed < 60; ++seed) {
    const double sigma = seed % 3 == 0 ? 0.0 : (seed % 3 == 1 ? 1.5 : 4.0);
    const cv::Mat m = random_blobs(61 + seed % 7, 47 + seed % 5, seed, sigma);
    const Region r = region_from_mask(m);
    EXPECT_EQ(region_area(r), static_cast<double>(cv::countNonZero(m))) << "seed " << seed;
    EXPECT_TRUE(masks_equal(rasterize_region(r, m.cols, m.rows), m)) << "seed " << seed;
    expect_oriented(r);
    for (const Polygon& p : r) with_holes += !p.holes.empty();
  }
  EXPECT_GT(with_holes, 0);  // the sample did exercise holes
}

// Nesting: every polygon rasterised on its own (outer and its holes) covers a disjoint part
// of the mask and together they cover it all. A hole attached to the wrong outer would show
// up as pixels outside that outer (even-odd) and as a missing hole in its true polygon.
TEST(RegionNesting, EveryHoleBelongsToItsOuter) {
  int holes = 0;
  for (unsigned seed = 0; seed < 30; ++seed) {
    const cv::Mat m = random_blobs(90, 70, seed + 1000, 1.2 + 0.1 * (seed % 10), 0.3 + 0.02 * (seed % 20));
    for (int mode = 0; mode < 2; ++mode) {
      const Region r = mode == 0 ? region_from_mask(m) : region_from_image(m, 127.5);
      cv::Mat sum(m.size(), CV_32SC1, cv::Scalar(0));
      for (const Polygon& p : r) {
        holes += static_cast<int>(p.holes.size());
        cv::Mat one;
        rasterize_region({p}, m.cols, m.rows).convertTo(one, CV_32S, 1.0 / 255);
        sum += one;
      }
      double mx;
      cv::minMaxLoc(sum, nullptr, &mx);
      EXPECT_LE(mx, 1.0) << "seed " << seed << " mode " << mode;
      cv::Mat covered = sum > 0;
      EXPECT_TRUE(masks_equal(covered, m)) << "seed " << seed << " mode " << mode;
    }
  }
  EXPECT_GT(holes, 50);
}

TEST(RegionFromMask, AcceptsOtherTypes) {
  const cv::Mat m = random_blobs(40, 30, 7, 2.0);
  cv::Mat f;
  m.convertTo(f, CV_32F, 1.0 / 255);
  EXPECT_EQ(region_area(region_from_mask(f)), static_cast<double>(cv::countNonZero(m)));
  EXPECT_THROW(region_from_mask(cv::Mat(3, 3, CV_8UC3)), std::invalid_argument);
}

// Half-open pixel-centre convention: a centre is inside iff it lies in (x0, x1] x [y0, y1).
TEST(RasterizeRegion, PixelCentreSamplingIsExact) {
  const Region r{Polygon{rect(2.3, 1.0, 7.5, 4.0), {}}};
  const cv::Mat m = rasterize_region(r, 10, 6);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 10; ++x) {
      const bool in = x > 2.3 && x <= 7.5 && y >= 1 && y < 4;
      EXPECT_EQ(m.at<std::uint8_t>(y, x) != 0, in) << x << "," << y;
    }
  // A triangle against a direct point-in-triangle test at every centre (no centre lies on
  // its edges: the vertices are irrational-ish).
  const std::vector<Vec2d> tri{{3.17, 2.71}, {41.3, 9.93}, {12.9, 33.4}};
  const cv::Mat t = rasterize_region({Polygon{tri, {}}}, 48, 40);
  auto side = [](const Vec2d& a, const Vec2d& b, const Vec2d& p) {
    return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
  };
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 48; ++x) {
      const Vec2d p(x, y);
      const bool in = side(tri[0], tri[1], p) > 0 && side(tri[1], tri[2], p) > 0 && side(tri[2], tri[0], p) > 0;
      EXPECT_EQ(t.at<std::uint8_t>(y, x) != 0, in) << x << "," << y;
    }
  // Holes are even-odd; regions clip at the image border.
  const Region ring{Polygon{rect(-5.5, -5.5, 9.5, 9.5), {reversed(rect(1.5, 1.5, 3.5, 3.5))}}};
  const cv::Mat g = rasterize_region(ring, 6, 6);
  EXPECT_EQ(cv::countNonZero(g), 36 - 4);
  EXPECT_EQ(g.at<std::uint8_t>(2, 2), 0);
}

TEST(RegionFromImage, RasterizedDiscAreaWithinBound) {
  const double r = 60, cx = 80.37, cy = 70.61;
  const cv::Mat m = disc_mask(160, 140, cx, cy, r);
  const Region reg = region_from_image(m, 127.5);
  ASSERT_EQ(reg.size(), 1u);
  EXPECT_TRUE(reg[0].holes.empty());
  expect_oriented(reg);
  // Every vertex is the midpoint of a lattice edge whose ends straddle the circle, so it is
  // within 1/2 px of the circle, and the contour lies in the band |rho - r| <= sqrt(2)/2 of
  // the straddling cells: |area - pi r^2| <= 2 pi r * sqrt(2)/2 (a rigorous, loose bound).
  const double area = region_area(reg);
  EXPECT_NEAR(area, kPi * r * r, 2 * kPi * r * std::sqrt(0.5));
  // On a (supersampled) coverage image at level 1/2 the interpolated contour follows the
  // circle closely: the band is the per-pixel coverage quantisation (1/s^2 = 1/256 of a
  // pixel per boundary pixel) plus the O(1/r) curvature error of linear interpolation; a
  // budget of 0.02 px^2 per unit length of boundary covers both with margin.
  const cv::Mat c = disc_coverage(160, 140, cx, cy, r, 16);
  const Region rc = region_from_image(c, 0.5);
  ASSERT_EQ(rc.size(), 1u);
  EXPECT_NEAR(region_area(rc), kPi * r * r, 0.02 * 2 * kPi * r);
  std::printf("disc r=%g: pi r^2=%.3f mask-contour area=%.3f (err %.3f) coverage-contour area=%.3f (err %.4f)\n", r,
              kPi * r * r, area, area - kPi * r * r, region_area(rc), region_area(rc) - kPi * r * r);
}

TEST(RegionFromImage, AnnulusKeepsItsHole) {
  const double r1 = 15, r2 = 30;
  const cv::Mat outer = disc_coverage(80, 70, 40.2, 35.7, r2, 8), inner = disc_coverage(80, 70, 40.2, 35.7, r1, 8);
  const cv::Mat ann = outer - inner;
  const Region reg = region_from_image(ann, 0.5);
  ASSERT_EQ(reg.size(), 1u);
  ASSERT_EQ(reg[0].holes.size(), 1u);
  expect_oriented(reg);
  // Same budget as the disc test, on both boundaries.
  EXPECT_NEAR(region_area(reg), kPi * (r2 * r2 - r1 * r1), 0.02 * 2 * kPi * (r1 + r2));
  // Island inside the hole: three nested loops -> two polygons.
  const cv::Mat island = ann + disc_coverage(80, 70, 40.2, 35.7, 6, 8);
  const Region r3 = region_from_image(island, 0.5);
  ASSERT_EQ(r3.size(), 2u);
  EXPECT_EQ(r3[0].holes.size() + r3[1].holes.size(), 1u);
}

TEST(RegionFromImage, ImageTypesAgreeAndPaddingClosesBorderBlobs) {
  // A blob touching the border is closed by the outside padding.
  cv::Mat m = random_blobs(50, 40, 3, 3.0);
  m.row(0).setTo(255);
  cv::Mat f32, f64;
  m.convertTo(f32, CV_32F, 1.0 / 255);
  m.convertTo(f64, CV_64F, 1.0 / 255);
  const Region a = region_from_image(m, 127.5), b = region_from_image(f32, 0.5), c = region_from_image(f64, 0.5);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), c.size());
  EXPECT_EQ(region_area(a), region_area(b));  // all crossings at t = 1/2 exactly
  EXPECT_EQ(region_area(a), region_area(c));
  EXPECT_EQ(region_vertex_count(a), region_vertex_count(c));
  // The contour of a binary mask at 1/2 samples back to the same pixel centres.
  EXPECT_TRUE(masks_equal(rasterize_region(a, m.cols, m.rows), m));
  expect_oriented(a);
  EXPECT_THROW(region_from_image(cv::Mat(3, 3, CV_16UC1, cv::Scalar(0)), 1.0), std::invalid_argument);
  EXPECT_THROW(region_from_image(m, std::nan("")), std::invalid_argument);
  EXPECT_TRUE(region_from_image(cv::Mat(), 0.5).empty());
  EXPECT_TRUE(region_from_image(m, 255.0).empty());
}

TEST(RegionFromImage, SaddlesFollowTheCellMean) {
  // 2x2 checkerboard: values 1 at (0,0),(1,1), 0 elsewhere; centre mean 0.5.
  cv::Mat img = (cv::Mat_<float>(2, 2) << 1, 0, 0, 1);
  EXPECT_EQ(region_from_image(img, 0.4).size(), 1u);  // mean > iso: joined
  EXPECT_EQ(region_from_image(img, 0.6).size(), 2u);  // mean < iso: separate
}
