// Registration recovers known similarity transforms applied to real mold silhouettes.

#include <meltlab/datasets/molds.h>
#include <meltlab/render/raster/silhouette.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/metrics.h>
#include <meltlab/verify/registration.h>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <numbers>

namespace meltlab::verify {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// The mold seen from above at 3 px/mm in a 1024x768 image (a ~550 px silhouette, so the
/// moved copies stay inside the image).
cv::Mat mold_mask(datasets::Mold mold) {
  const auto mesh = sim::TriMesh<double>::from_indexed(datasets::mold_mesh(mold));
  render::OrthographicTopDown cam = render::OrthographicTopDown::from_pixels_per_mm(1024, 768, 3.0, {0, 0});
  return render::silhouette_mask(mesh, cam);
}

Similarity2D make(double scale, double deg, double tx, double ty) {
  Similarity2D t;
  t.scale = scale;
  t.angle_rad = deg * kDeg;
  t.translation = {tx, ty};
  return t;
}

/// The similarity as seen about the image centre (the parameters a user would read).
double max_point_error(const Similarity2D& a, const Similarity2D& b, cv::Size size) {
  double e = 0;
  for (const Vec2d& p : {Vec2d(0, 0), Vec2d(size.width, 0), Vec2d(0, size.height), Vec2d(size.width, size.height),
                         Vec2d(size.width / 2.0, size.height / 2.0)})
    e = std::max(e, (a.apply(p) - b.apply(p)).norm());
  return e;
}

TEST(Similarity, ComposeInverseAndMatrixAgree) {
  const Similarity2D a = make(1.3, 25, 4, -7), b = make(0.8, -60, -11, 3);
  const Vec2d p(17.5, -3.25);
  EXPECT_LT((compose(a, b).apply(p) - a.apply(b.apply(p))).norm(), 1e-12);
  EXPECT_LT((a.inverse().apply(a.apply(p)) - p).norm(), 1e-12);
  const cv::Mat m = a.matrix();
  const Vec2d q(m.at<double>(0, 0) * p.x() + m.at<double>(0, 1) * p.y() + m.at<double>(0, 2),
                m.at<double>(1, 0) * p.x() + m.at<double>(1, 1) * p.y() + m.at<double>(1, 2));
  EXPECT_LT((q - a.apply(p)).norm(), 1e-12);
}

// The photo is the render moved by a known similarity; registration must find it. The
// masks are binary, so the recovered transform is exact only to the pixelisation of the
// boundary: 0.75 px at any image corner is a tight bound for a ~550 px object (an error of
// 0.1 degree alone moves a corner 1.1 px).
constexpr double kCornerTolerancePx = 0.75;

class Recovers : public ::testing::TestWithParam<std::tuple<datasets::Mold, RegistrationOptions::Refine>> {};

TEST_P(Recovers, KnownSimilarity) {
  const auto [mold, refine] = GetParam();
  const cv::Mat render = mold_mask(mold);
  for (const Similarity2D& truth : {make(1.0, 0, 9, -6), make(1.04, 4, -15, 11), make(0.97, -8, 20, 5)}) {
    const cv::Mat photo = warp_mask(render, truth, render.size());
    RegistrationOptions o;
    o.refine = refine;
    const RegistrationResult r = register_masks(photo, render, o);
    EXPECT_LT(max_point_error(r.render_to_photo, truth, render.size()), kCornerTolerancePx)
        << datasets::mold_name(mold) << " " << r.method << " scale " << r.render_to_photo.scale << " angle "
        << r.render_to_photo.angle_rad / kDeg << " t " << r.render_to_photo.translation.transpose();
    EXPECT_LT(r.P_after, 0.01) << r.method;
    EXPECT_LE(r.P_after, r.P_before);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Molds, Recovers,
    ::testing::Combine(::testing::Values(datasets::Mold::kGiraffe, datasets::Mold::kAirplane, datasets::Mold::kShip),
                       ::testing::Values(RegistrationOptions::Refine::kIcp, RegistrationOptions::Refine::kEcc)));

TEST(Registration, MomentsAloneGetClose) {
  const cv::Mat render = mold_mask(datasets::Mold::kGiraffe);
  const Similarity2D truth = make(1.02, 3, 12, -8);
  const cv::Mat photo = warp_mask(render, truth, render.size());
  RegistrationOptions o;
  o.refine = RegistrationOptions::Refine::kNone;
  const RegistrationResult r = register_masks(photo, render, o);
  // Moments fix centroid and area exactly; the principal axis of an irregular shape is
  // good to about a degree.
  EXPECT_NEAR(r.render_to_photo.scale, truth.scale, 0.005);
  EXPECT_NEAR(r.render_to_photo.angle_rad, truth.angle_rad, 1.5 * kDeg);
  EXPECT_LT(r.P_after, 0.05);
}

TEST(Registration, FixedScaleAndRotationAreRespected) {
  const cv::Mat render = mold_mask(datasets::Mold::kAirplane);
  const Similarity2D truth = make(1.0, 0, -7, 13);
  const cv::Mat photo = warp_mask(render, truth, render.size());
  RegistrationOptions o;
  o.allow_scale = false;
  o.allow_rotation = false;
  const RegistrationResult r = register_masks(photo, render, o);
  EXPECT_EQ(r.render_to_photo.scale, 1.0);
  EXPECT_EQ(r.render_to_photo.angle_rad, 0.0);
  EXPECT_NEAR(r.render_to_photo.translation.x(), -7, 0.3);
  EXPECT_NEAR(r.render_to_photo.translation.y(), 13, 0.3);
}

TEST(Registration, IdenticalMasksNeedNoMove) {
  const cv::Mat render = mold_mask(datasets::Mold::kShip);
  const RegistrationResult r = register_masks(render, render);
  EXPECT_EQ(r.P_before, 0.0);
  EXPECT_LT(max_point_error(r.render_to_photo, Similarity2D::identity(), render.size()), 0.05);
  EXPECT_EQ(r.P_after, 0.0);
}

TEST(Registration, EmptyOrMismatchedMasksAreErrors) {
  const cv::Mat render = mold_mask(datasets::Mold::kShip);
  const cv::Mat empty = cv::Mat::zeros(render.size(), CV_8UC1);
  EXPECT_THROW(register_masks(empty, render), InputError);
  EXPECT_THROW(register_masks(render, empty), InputError);
  EXPECT_THROW(register_masks(render, cv::Mat::zeros(10, 10, CV_8UC1)), std::invalid_argument);
}

TEST(Registration, TransformRegionMatchesWarpMask) {
  const cv::Mat render = mold_mask(datasets::Mold::kGiraffe);
  const Similarity2D t = make(1.1, 10, 5, -4);
  const Region moved = transform_region(region_from_mask(render), t);
  EXPECT_NEAR(region_area(moved), t.scale * t.scale * cv::countNonZero(render), 1e-6 * cv::countNonZero(render));
  // Nearest-neighbour warping and exact polygon transformation agree up to the boundary
  // pixelisation: P below perimeter/area ~ 0.02 for this silhouette.
  const cv::Mat warped = warp_mask(render, t, render.size());
  EXPECT_LT(compare_masks(warped, rasterize_region(moved, render.cols, render.rows)).P, 0.02);
}

}  // namespace
}  // namespace meltlab::verify
