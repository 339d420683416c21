#pragma once
// Registration of a rendered silhouette onto a photographed one (monograph §9.1: "the render
// viewpoint matches the camera pose"; Fig. 8.4 suggests manual placement). A 2-D similarity
//   p_photo = s R(angle) p_render + t          (pixel coordinates, OpenCV convention)
// is estimated from image moments (centroid, area, principal axis) and refined either by
// contour ICP (nearest boundary points, closed-form similarity by Eigen::umeyama) or by
// OpenCV's ECC (findTransformECC, Euclidean motion, on blurred masks, after the moment scale).

#include <meltlab/verify/region.h>

#include <opencv2/core.hpp>

#include <string>

namespace meltlab::verify {

struct Similarity2D {
  double scale = 1.0;
  double angle_rad = 0.0;
  Vec2d translation = Vec2d::Zero();

  Vec2d apply(const Vec2d& p_render) const;
  Similarity2D inverse() const;
  /// 2x3 CV_64F matrix for cv::warpAffine (maps render pixels to photo pixels).
  cv::Mat matrix() const;
  static Similarity2D identity() { return {}; }
};

/// The composition a ∘ b (apply b, then a).
Similarity2D compose(const Similarity2D& a, const Similarity2D& b);

struct RegistrationOptions {
  enum class Refine { kNone, kIcp, kEcc };
  Refine refine = Refine::kIcp;
  bool allow_scale = true;
  bool allow_rotation = true;
  int max_iterations = 60;
  double tolerance_px = 1e-3;  ///< ICP stops when the transform moves points less than this
  double ecc_blur_sigma_px = 3.0;
};

struct RegistrationResult {
  Similarity2D render_to_photo;
  double P_before = 1.0;  ///< P of the unregistered masks
  double P_after = 1.0;   ///< P after warping the render with the result
  int iterations = 0;
  bool converged = false;
  std::string method;  ///< "moments", "moments+icp", "moments+ecc"
};

/// Registers `render` onto `photo` (binary CV_8UC1 masks of the same size, nonzero = inside).
/// Throws InputError if either mask is empty.
RegistrationResult register_masks(const cv::Mat& photo, const cv::Mat& render, const RegistrationOptions& options = {});

/// Warps a binary mask with a similarity (nearest neighbour; output size `size`).
cv::Mat warp_mask(const cv::Mat& mask, const Similarity2D& render_to_photo, cv::Size size);
/// Applies a similarity to every vertex of a region.
Region transform_region(const Region& region, const Similarity2D& t);

}  // namespace meltlab::verify
