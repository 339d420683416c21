#pragma once
// The P measure of the monograph (§8.3, Eq. 8.1) and related similarity measures between a
// photographed contour A and a rendered contour B:
//   P = (S_A + S_B) / (S_A + S_I + S_B)
// with S_A the photo-only area, S_B the render-only area and S_I the common area. P = 0 for
// identical contours, 1 for disjoint ones; P = 1 - IoU (the Jaccard distance).
// Raster versions count pixels (as the monograph does); exact versions take the areas of
// polygon Boolean operations (CGAL, exact arithmetic) — the limit the raster P converges to.

#include <meltlab/verify/region.h>

#include <opencv2/core.hpp>

#include <cstdint>

namespace meltlab::verify {

struct AreaComparison {
  double S_A = 0;   ///< photo only (pixels, or px² for exact areas)
  double S_B = 0;   ///< render only
  double S_I = 0;   ///< common
  double P = 0;     ///< Eq. 8.1; defined as 0 when both are empty
  double IoU = 0;   ///< S_I / (S_A + S_I + S_B) = 1 - P
  double Dice = 0;  ///< 2 S_I / (2 S_I + S_A + S_B)
};

/// Pixel counts of two binary masks of the same size (nonzero = inside). Throws
/// std::invalid_argument on size/type mismatch.
AreaComparison compare_masks(const cv::Mat& photo, const cv::Mat& render);

/// Soft version for coverage images in [0, 1] (CV_32FC1): S_I = Σ min(a, b),
/// S_A = Σ a - S_I, S_B = Σ b - S_I. Equals compare_masks on 0/1 images.
AreaComparison compare_coverage(const cv::Mat& photo, const cv::Mat& render);

/// Exact areas by polygon Boolean operations (CGAL Polygon_set_2 with an exact kernel).
AreaComparison compare_regions_exact(const Region& photo, const Region& render);

struct ContourDistances {
  double hausdorff = 0;  ///< symmetric Hausdorff distance between the boundaries
  double mean = 0;       ///< mean of the two directed mean distances
  double photo_to_render_max = 0, render_to_photo_max = 0;
  double photo_to_render_mean = 0, render_to_photo_mean = 0;
};

/// Distances between the boundaries of two regions, in the regions' units (pixels): every
/// boundary is sampled at `spacing` and each sample's distance to the other boundary's
/// segments is exact. Infinite if one region is empty and the other is not.
ContourDistances contour_distances(const Region& photo, const Region& render, double spacing = 0.5);

}  // namespace meltlab::verify
