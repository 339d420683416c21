#pragma once
// Planar regions in pixel coordinates (OpenCV's convention: integer coordinates are pixel
// centres, v downwards): a union of polygons, each with an outer loop and hole loops.
// Loops are closed implicitly (the last point connects to the first). Outer loops are
// counter-clockwise in (u, v) *as numbers* (positive shoelace area), holes clockwise.

#include <Eigen/Core>

#include <opencv2/core.hpp>

#include <vector>

namespace meltlab::verify {

using Vec2d = Eigen::Vector2d;

struct Polygon {
  std::vector<Vec2d> outer;
  std::vector<std::vector<Vec2d>> holes;
};

using Region = std::vector<Polygon>;

/// Signed shoelace area of a loop (positive for counter-clockwise).
double loop_area(const std::vector<Vec2d>& loop);
/// Area of a region: outer areas minus hole areas (loops must not overlap).
double region_area(const Region& region);
/// Total number of vertices of all loops.
std::size_t region_vertex_count(const Region& region);

/// Sub-pixel contour of an image at level `iso` by marching squares with linear
/// interpolation between pixel centres (values > iso are inside). The image is CV_8UC1,
/// CV_32FC1 or CV_64FC1 (e.g. a coverage image, or a smoothed foreground probability);
/// pixels outside the image count as outside. Loops are assembled, oriented (outer CCW,
/// holes CW) and nested; saddle cells are resolved by the cell's mean value.
Region region_from_image(const cv::Mat& image, double iso);

/// Pixel-exact region of a binary mask (nonzero = inside): the boundaries of the pixel
/// squares, i.e. the region whose area is exactly the pixel count.
Region region_from_mask(const cv::Mat& mask);

/// Rasterises a region into a CV_8UC1 mask (255 inside) of the given size, sampling pixel
/// centres (even-odd over all loops).
cv::Mat rasterize_region(const Region& region, int width, int height);

}  // namespace meltlab::verify
