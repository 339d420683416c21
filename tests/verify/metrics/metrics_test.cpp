// The P measure (Eq. 8.1): closed forms on polygons and masks, invariances, errors; and the
// boundary distances.

#include "shapes.h"

#include <meltlab/verify/metrics.h>
#include <meltlab/verify/region.h>

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>

using namespace meltlab::verify;
using namespace meltlab::verify::testing;

namespace {

// Eq. 8.1 from the areas of A, B and A∩B.
double P_of(double a, double b, double i) { return (a + b - 2 * i) / (a + b - i); }

cv::Mat square_mask(int w, int h, int x0, int y0, int side) {
  cv::Mat m(h, w, CV_8UC1, cv::Scalar(0));
  m(cv::Rect(x0, y0, side, side)).setTo(255);
  return m;
}

}  // namespace

TEST(CompareMasks, IdenticalDisjointEmpty) {
  const cv::Mat a = random_blobs(64, 48, 1, 3.0);
  AreaComparison c = compare_masks(a, a);
  EXPECT_EQ(c.P, 0.0);
  EXPECT_EQ(c.IoU, 1.0);
  EXPECT_EQ(c.Dice, 1.0);
  EXPECT_EQ(c.S_I, cv::countNonZero(a));
  const cv::Mat b = ~a;  // complement: disjoint
  c = compare_masks(a, b);
  EXPECT_EQ(c.P, 1.0);
  EXPECT_EQ(c.IoU, 0.0);
  const cv::Mat z(48, 64, CV_8UC1, cv::Scalar(0));
  c = compare_masks(z, z);
  EXPECT_EQ(c.P, 0.0);  // defined as 0 when both are empty
  EXPECT_EQ(compare_masks(a, z).P, 1.0);
}

TEST(CompareMasks, SymmetricAndComplementary) {
  for (unsigned seed = 0; seed < 20; ++seed) {
    const cv::Mat a = random_blobs(70, 50, seed, 2.5), b = random_blobs(70, 50, seed + 100, 2.5);
    const AreaComparison ab = compare_masks(a, b), ba = compare_masks(b, a);
    EXPECT_EQ(ab.P, ba.P);
    EXPECT_EQ(ab.S_A, ba.S_B);
    EXPECT_EQ(ab.S_I, cv::countNonZero(a & b));
    EXPECT_EQ(ab.S_A + ab.S_B, cv::countNonZero(a ^ b));
    EXPECT_NEAR(ab.P + ab.IoU, 1.0, 1e-15);  // P = 1 - IoU up to one rounding
  }
}

TEST(CompareMasks, MismatchedInputsThrow) {
  const cv::Mat a(10, 10, CV_8UC1, cv::Scalar(0)), b(10, 11, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(compare_masks(a, b), std::invalid_argument);
  EXPECT_THROW(compare_masks(a, cv::Mat(10, 10, CV_32FC1, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(compare_coverage(cv::Mat(10, 10, CV_32FC1), cv::Mat(11, 10, CV_32FC1)), std::invalid_argument);
  EXPECT_THROW(compare_coverage(a, a), std::invalid_argument);  // not CV_32FC1
}

TEST(CompareCoverage, EqualsCompareMasksOnBinaryImages) {
  for (unsigned seed = 0; seed < 10; ++seed) {
    const cv::Mat a = random_blobs(53, 41, seed, 2.0), b = random_blobs(53, 41, seed + 7, 2.0);
    cv::Mat fa, fb;
    a.convertTo(fa, CV_32F, 1.0 / 255);
    b.convertTo(fb, CV_32F, 1.0 / 255);
    const AreaComparison m = compare_masks(a, b), c = compare_coverage(fa, fb);
    EXPECT_EQ(m.S_A, c.S_A);  // sums of 0/1 values are exact
    EXPECT_EQ(m.S_B, c.S_B);
    EXPECT_EQ(m.S_I, c.S_I);
    EXPECT_EQ(m.P, c.P);
  }
  // Soft overlap: a = 0.75, b = 0.25 everywhere -> S_I = 0.25 n, S_A = 0.5 n, S_B = 0.
  const cv::Mat a(4, 4, CV_32FC1, cv::Scalar(0.75)), b(4, 4, CV_32FC1, cv::Scalar(0.25));
  const AreaComparison c = compare_coverage(a, b);
  EXPECT_EQ(c.S_I, 4.0);
  EXPECT_EQ(c.S_A, 8.0);
  EXPECT_EQ(c.S_B, 0.0);
  EXPECT_EQ(c.P, 8.0 / 12.0);
}

// Two axis-aligned squares of side a offset by (dx, dy): A_I = (a - |dx|)(a - |dy|).
// Polygons: exact areas of exactly representable vertices, so P matches the closed form to
// the rounding of the closed form itself (1e-12 is generous).
TEST(CompareRegionsExact, OffsetSquaresClosedForm) {
  const double a = 10.0;
  for (const auto& [dx, dy] :
       {std::pair{0.0, 0.0}, {3.25, 1.5}, {-2.125, 7.75}, {0.1, -0.3}, {9.9, 9.9}, {12.0, 0.0}}) {
    const Region A{Polygon{rect(0, 0, a, a), {}}}, B{Polygon{rect(dx, dy, dx + a, dy + a), {}}};
    const double i = std::max(0.0, a - std::abs(dx)) * std::max(0.0, a - std::abs(dy));
    const AreaComparison c = compare_regions_exact(A, B);
    EXPECT_NEAR(c.P, P_of(a * a, a * a, i), 1e-12) << dx << "," << dy;
    EXPECT_NEAR(c.S_I, i, 1e-12);
    EXPECT_EQ(c.P, compare_regions_exact(B, A).P);  // symmetry
  }
}

// Pixel masks with integer offsets: the pixel counts are the closed form, exactly.
TEST(CompareMasks, OffsetSquaresExactOnIntegerOffsets) {
  const int a = 40;
  for (const auto& [dx, dy] : {std::pair{0, 0}, {3, 1}, {-7, 12}, {39, 39}, {25, -5}}) {
    const cv::Mat A = square_mask(200, 150, 60, 50, a), B = square_mask(200, 150, 60 + dx, 50 + dy, a);
    const double i = static_cast<double>((a - std::abs(dx)) * (a - std::abs(dy)));
    const AreaComparison c = compare_masks(A, B);
    EXPECT_EQ(c.S_I, i);
    EXPECT_EQ(c.S_A, a * a - i);
    EXPECT_DOUBLE_EQ(c.P, P_of(a * a, a * a, i));
    // and the exact comparison of their pixel-square regions agrees exactly
    const AreaComparison e = compare_regions_exact(region_from_mask(A), region_from_mask(B));
    EXPECT_EQ(e.S_I, i);
    EXPECT_DOUBLE_EQ(e.P, c.P);
  }
}

// Two discs of radius r, centres d apart, approximated by inscribed regular n-gons. The
// polygon misses delta = pi r^2 - ngon_area(r, n) of each disc (exactly computable), so its
// intersection and union areas are within 2 delta of the lens/union, and
// |P_poly - P| <= 2 delta / U' + I * 2 delta / (U U') with U' = U - 2 delta.
TEST(CompareRegionsExact, TwoDiscsLensClosedForm) {
  const double r = 50;
  const int n = 2048;
  const double delta = kPi * r * r - ngon_area(r, n);
  for (const double d : {0.0, 7.3, 25.0, 50.0, 81.2, 99.0}) {
    const Region A = disc_region(100, 100, r, n), B = disc_region(100 + d * 0.6, 100 + d * 0.8, r, n);
    const AreaComparison c = compare_regions_exact(A, B);
    const double I = lens_area(r, d), U = 2 * kPi * r * r - I, Up = U - 2 * delta;
    const double bound = 2 * delta / Up + I * 2 * delta / (U * Up);
    EXPECT_NEAR(c.P, disc_pair_P(r, d), bound) << "d=" << d;
    EXPECT_NEAR(c.S_I, I, 2 * delta);
    // |A| itself is the n-gon area, exactly up to rounding.
    EXPECT_NEAR(c.S_A + c.S_I, ngon_area(r, n), 1e-9 * r * r);
  }
  // Symmetry, disjointness.
  const Region A = disc_region(0, 0, r, n), B = disc_region(30, 5, r, n), F = disc_region(500, 0, r, n);
  EXPECT_EQ(compare_regions_exact(A, B).P, compare_regions_exact(B, A).P);
  EXPECT_EQ(compare_regions_exact(A, F).P, 1.0);
  EXPECT_EQ(compare_regions_exact(A, A).P, 0.0);
  EXPECT_EQ(compare_regions_exact({}, {}).P, 0.0);
  EXPECT_EQ(compare_regions_exact(A, {}).P, 1.0);
}

// Rasterised discs: the pixel count of a disc differs from pi r^2 by the lattice-point
// error (Gauss circle problem, well below 2 pi r * 0.5 in practice, and below the bound
// used here: half a pixel per unit length of every boundary involved).
TEST(CompareMasks, TwoDiscsLensOnPixels) {
  const double r = 120;
  for (const double d : {0.0, 30.0, 120.0, 200.0}) {
    const cv::Mat A = disc_mask(500, 300, 130.3, 150.6, r), B = disc_mask(500, 300, 130.3 + d, 150.6, r);
    const AreaComparison c = compare_masks(A, B);
    const double I = lens_area(r, d), U = 2 * kPi * r * r - I;
    const double slack = 0.5 * 2 * (2 * kPi * r);  // area slack: both boundaries, 1/2 px
    EXPECT_NEAR(c.P, disc_pair_P(r, d), 3 * slack / (U - slack)) << "d=" << d;
  }
}

// Nested shapes: A inside B gives P = 1 - |A| / |B|.
TEST(CompareRegionsExact, NestedShapes) {
  const Region small = disc_region(0.3, 0.7, 20, 720), big = disc_region(2.1, -1.4, 45, 720);
  const double Ps = 1 - ngon_area(20, 720) / ngon_area(45, 720);
  EXPECT_NEAR(compare_regions_exact(small, big).P, Ps, 1e-12);
  EXPECT_NEAR(compare_regions_exact(big, small).P, Ps, 1e-12);
  // Square with a hole against the full square: P = hole / square.
  const Region holed{Polygon{rect(0, 0, 10, 10), {reversed(rect(2, 3, 6, 8))}}};
  const Region full{Polygon{rect(0, 0, 10, 10), {}}};
  EXPECT_NEAR(compare_regions_exact(holed, full).P, 20.0 / 100.0, 1e-15);
  // A hole given counter-clockwise still reads as a hole (even-odd).
  const Region holed_ccw{Polygon{rect(0, 0, 10, 10), {rect(2, 3, 6, 8)}}};
  EXPECT_NEAR(compare_regions_exact(holed_ccw, full).P, 0.2, 1e-15);
  // Same on masks: pixel squares.
  cv::Mat hm(30, 30, CV_8UC1, cv::Scalar(0)), fm;
  hm(cv::Rect(5, 5, 20, 20)).setTo(255);
  fm = hm.clone();
  hm(cv::Rect(9, 11, 6, 4)).setTo(0);
  EXPECT_DOUBLE_EQ(compare_masks(hm, fm).P, 24.0 / 400.0);
  EXPECT_DOUBLE_EQ(compare_regions_exact(region_from_mask(hm), region_from_mask(fm)).P, 24.0 / 400.0);
}

// The exact comparison of pixel-square regions is the pixel count, exactly, on random masks
// with holes, islands and pinched corners (self-touching loops).
TEST(CompareRegionsExact, PixelRegionsReproducePixelCounts) {
  for (unsigned seed = 0; seed < 12; ++seed) {
    const double sigma = seed % 2 ? 2.0 : 0.0;
    const cv::Mat a = random_blobs(40, 32, seed, sigma), b = random_blobs(40, 32, seed + 50, sigma);
    const AreaComparison m = compare_masks(a, b);
    const AreaComparison e = compare_regions_exact(region_from_mask(a), region_from_mask(b));
    EXPECT_EQ(e.S_A, m.S_A) << seed;
    EXPECT_EQ(e.S_B, m.S_B) << seed;
    EXPECT_EQ(e.S_I, m.S_I) << seed;
  }
}

// ---- distances -----------------------------------------------------------------------------

// Concentric inscribed n-gons of radii r1 < r2: polygon k lies in the annulus
// [r_k cos(pi/n), r_k]. The vertices of the outer polygon are samples at distance >= r2 - r1
// from the inner one, and no point is farther than r2 - r1 cos(pi/n): so
// r2 - r1 <= H <= r2 - r1 cos(pi/n), and the means lie in [r2 cos(pi/n) - r1, r2 - r1 cos(pi/n)].
TEST(ContourDistances, ConcentricCircles) {
  const double r1 = 40, r2 = 47.5;
  const int n = 1000;
  const double c = std::cos(kPi / n);
  const Region A = disc_region(10, 20, r1, n), B = disc_region(10, 20, r2, n, 0.77);
  const ContourDistances d = contour_distances(A, B, 0.5), e = contour_distances(B, A, 0.5);
  EXPECT_GE(d.hausdorff, r2 - r1);
  EXPECT_LE(d.hausdorff, r2 - r1 * c);
  EXPECT_GE(d.mean, r2 * c - r1);
  EXPECT_LE(d.mean, r2 - r1 * c);
  EXPECT_EQ(d.hausdorff, e.hausdorff);  // symmetry
  EXPECT_EQ(d.mean, e.mean);
  EXPECT_EQ(d.photo_to_render_max, e.render_to_photo_max);
}

// The grid search equals brute force (same exact point-to-segment formula).
TEST(ContourDistances, GridSearchEqualsBruteForce) {
  for (unsigned seed = 0; seed < 5; ++seed) {
    const Region a = region_from_image(random_blobs(60, 50, seed, 3.0), 127.5);
    const Region b = region_from_image(random_blobs(60, 50, seed + 9, 3.0), 127.5);
    const double spacing = 0.7;
    const ContourDistances d = contour_distances(a, b, spacing);
    // brute force over the same samples
    auto segs = [](const Region& r) {
      std::vector<std::pair<Vec2d, Vec2d>> s;
      for (const Polygon& p : r) {
        auto add = [&](const std::vector<Vec2d>& l) {
          for (std::size_t i = 0; i < l.size(); ++i) s.emplace_back(l[i], l[(i + 1) % l.size()]);
        };
        add(p.outer);
        for (const auto& h : p.holes) add(h);
      }
      return s;
    };
    auto directed = [&](const Region& from, const Region& to) {
      const auto sf = segs(from), st = segs(to);
      double mx = 0;
      for (const auto& [a0, a1] : sf) {
        const auto n = static_cast<int>(std::max(1.0, std::ceil((a1 - a0).norm() / spacing)));
        for (int k = 0; k < n; ++k) {
          const Vec2d p = a0 + (a1 - a0) * (static_cast<double>(k) / n);
          double best = std::numeric_limits<double>::infinity();
          for (const auto& [b0, b1] : st) {
            const Vec2d dd = b1 - b0;
            const double t = std::clamp(dd.squaredNorm() > 0 ? (p - b0).dot(dd) / dd.squaredNorm() : 0.0, 0.0, 1.0);
            best = std::min(best, (b0 + t * dd - p).squaredNorm());
          }
          mx = std::max(mx, std::sqrt(best));
        }
      }
      return mx;
    };
    EXPECT_EQ(d.photo_to_render_max, directed(a, b)) << seed;
    EXPECT_EQ(d.render_to_photo_max, directed(b, a)) << seed;
  }
}

TEST(ContourDistances, EmptyAndInvalid) {
  const Region a = disc_region(0, 0, 5, 64);
  const ContourDistances both = contour_distances({}, {});
  EXPECT_EQ(both.hausdorff, 0.0);
  EXPECT_EQ(both.mean, 0.0);
  EXPECT_TRUE(std::isinf(contour_distances(a, {}).hausdorff));
  EXPECT_TRUE(std::isinf(contour_distances({}, a).mean));
  EXPECT_NEAR(contour_distances(a, a).hausdorff, 0.0, 1e-12);  // samples lie on the segments up to rounding
  EXPECT_THROW(contour_distances(a, a, 0.0), std::invalid_argument);
  EXPECT_THROW(contour_distances(a, a, std::nan("")), std::invalid_argument);
}
