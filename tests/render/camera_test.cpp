// Cameras (camera.h): projection conventions, agreement with OpenCV, rays and projections
// as inverses, crops, YAML parsing and the JSON round trip.

#include <meltlab/render/camera.h>
#include <meltlab/core/error.h>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <random>
#include <vector>

namespace meltlab::render {
namespace {

// Orthographic mapping is a scale and a shift of doubles: exact up to a few ulps of ~1e3 px.
constexpr double kOrthoTolPx = 1e-9;
// Our distortion polynomial and OpenCV's are the same formula evaluated in a different order:
// agreement to round-off of ~1e3 px coordinates (1e-13 relative) is far below 1e-8 px.
constexpr double kProjectTolPx = 1e-8;

std::string message_of(const std::string& yaml) {
  try {
    parse_camera(YAML::Load(yaml), "cams.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(OrthographicTopDown, MapsKnownPoints) {
  const auto cam = OrthographicTopDown::from_pixels_per_mm(2048, 1536, 10.0, Vec2d(0.01, -0.02));
  EXPECT_DOUBLE_EQ(cam.pixels_per_unit, 10000.0);
  const Camera c = cam;
  // The centre maps to the middle of the image ((w - 1)/2, (h - 1)/2), height is ignored.
  const RayGenerator rays(c);
  const Projection a = rays.project(Vec3d(0.01, -0.02, 0.5));
  EXPECT_TRUE(a.in_front);
  const Vec2d p0 = a.pixel;
  EXPECT_NEAR(p0.x(), 1023.5, kOrthoTolPx);
  EXPECT_NEAR(p0.y(), 767.5, kOrthoTolPx);
  // 1 mm to +x is 10 px to the right; 1 mm to +y is 10 px up (smaller v).
  const Vec2d p1 = rays.project(Vec3d(0.011, -0.02, 0.0)).pixel;
  EXPECT_NEAR(p1.x(), 1033.5, kOrthoTolPx);
  EXPECT_NEAR(p1.y(), 767.5, kOrthoTolPx);
  const Vec2d p2 = rays.project(Vec3d(0.01, -0.019, 0.0)).pixel;
  EXPECT_NEAR(p2.x(), 1023.5, kOrthoTolPx);
  EXPECT_NEAR(p2.y(), 757.5, kOrthoTolPx);
  EXPECT_EQ(camera_width(c), 2048);
  EXPECT_EQ(camera_height(c), 1536);
}

TEST(Pinhole, ProjectionEqualsOpenCvProjectPoints) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Pinhole p = Pinhole::look_at(1600, 1200, 1500.0, Vec3d(0.3, -0.4, 2.0), Vec3d(0.0, 0.05, 0.0), Vec3d(0, 1, 0));
  p.fy = 1530.0;
  p.cx = 790.25;
  p.cy = 610.75;
  p.distortion = {-0.21, 0.08, 0.0013, -0.0021, -0.015};
  EXPECT_TRUE(p.distorted());
  std::vector<cv::Point3d> pts;
  std::vector<Vec3d> world;
  for (int i = 0; i < 500; ++i) {
    const Vec3d w(0.4 * U(rng), 0.4 * U(rng), 0.3 * U(rng));
    world.push_back(w);
    pts.emplace_back(w.x(), w.y(), w.z());
  }
  cv::Mat R, rvec, K = (cv::Mat_<double>(3, 3) << p.fx, 0, p.cx, 0, p.fy, p.cy, 0, 0, 1);
  const Eigen::Matrix3d Re = p.camera_from_world.linear();
  cv::eigen2cv(Re, R);
  cv::Rodrigues(R, rvec);
  const Vec3d t = p.camera_from_world.translation();
  const cv::Mat tvec = (cv::Mat_<double>(3, 1) << t.x(), t.y(), t.z());
  const cv::Mat dist =
      (cv::Mat_<double>(1, 5) << p.distortion[0], p.distortion[1], p.distortion[2], p.distortion[3], p.distortion[4]);
  std::vector<cv::Point2d> img;
  cv::projectPoints(pts, rvec, tvec, K, dist, img);
  const RayGenerator rays(p);
  for (std::size_t i = 0; i < world.size(); ++i) {
    const auto [uv, depth, distance, ok] = rays.project(world[i]);
    ASSERT_TRUE(ok);
    // Rodrigues round-trips R to ~1e-15, i.e. ~1e-12 px here: inside kProjectTolPx.
    EXPECT_NEAR(uv.x(), img[i].x, kProjectTolPx) << i;
    EXPECT_NEAR(uv.y(), img[i].y, kProjectTolPx) << i;
  }
}

TEST(Pinhole, PointBehindTheCameraIsFlagged) {
  const RayGenerator rays(Pinhole::look_at(640, 480, 500.0, Vec3d(0, 0, 1), Vec3d(0, 0, 0)));
  const Projection ahead = rays.project(Vec3d(0, 0, 0));
  EXPECT_TRUE(ahead.in_front);
  EXPECT_DOUBLE_EQ(ahead.depth, 1.0);
  const Projection behind = rays.project(Vec3d(0, 0, 2));
  EXPECT_FALSE(behind.in_front);
  EXPECT_DOUBLE_EQ(behind.depth, -1.0);
  EXPECT_TRUE(std::isnan(behind.pixel.x()));
  EXPECT_FALSE(rays.project(Vec3d(0.1, 0, 1)).in_front);  // in the camera plane (z_camera = 0)
}

TEST(Pinhole, LookAtPutsTheTargetAtThePrincipalPointWithUpUp) {
  for (const Vec3d& eye : {Vec3d(0, 0, 3), Vec3d(1, -2, 0.5), Vec3d(-0.3, 0.2, -4)}) {
    const Vec3d target(0.1, 0.2, 0.05);
    const Pinhole p = Pinhole::look_at(2048, 1536, 1800.0, eye, target, Vec3d(0, 0, 1) + Vec3d(0, 1, 0));
    const auto [uv, depth, distance, ok] = RayGenerator(p).project(target);
    ASSERT_TRUE(ok);
    EXPECT_NEAR(depth, (target - eye).norm(), 1e-12);  // the target is on the optical axis
    // Rotation + division by the distance: round-off of ~1e3 px coordinates.
    EXPECT_NEAR(uv.x(), 1023.5, 1e-9);
    EXPECT_NEAR(uv.y(), 767.5, 1e-9);
    // The rotation is proper and orthonormal.
    const Eigen::Matrix3d R = p.camera_from_world.linear();
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  }
  // Looking straight down with up = +y: world +x is image right, world +y is image up.
  const RayGenerator down(Pinhole::look_at(640, 480, 500.0, Vec3d(0, 0, 2), Vec3d(0, 0, 0)));
  const Vec2d c0 = down.project(Vec3d(0, 0, 0)).pixel;
  const Vec2d cx = down.project(Vec3d(0.1, 0, 0)).pixel;
  const Vec2d cy = down.project(Vec3d(0, 0.1, 0)).pixel;
  EXPECT_GT(cx.x(), c0.x() + 20);
  EXPECT_NEAR(cx.y(), c0.y(), 1e-9);
  EXPECT_LT(cy.y(), c0.y() - 20);
  EXPECT_NEAR(cy.x(), c0.x(), 1e-9);
}

// A pinhole with every intrinsic off its default and a strong distortion, looking obliquely.
Pinhole oblique_distorted_pinhole() {
  Pinhole p = Pinhole::look_at(640, 480, 520.0, Vec3d(0.3, -0.4, 0.9), Vec3d(0.02, 0.01, 0.0), Vec3d(0, 1, 0));
  p.fy = 530.0;
  p.cx = 322.25;
  p.cy = 236.75;
  p.distortion = {-0.21, 0.08, 0.0013, -0.0021, -0.015};
  return p;
}

std::vector<Camera> cameras_of_every_kind() {
  Pinhole undistorted = oblique_distorted_pinhole();
  undistorted.distortion = {0, 0, 0, 0, 0};
  return {OrthographicTopDown::from_pixels_per_mm(640, 480, 3.0, Vec2d(0.012, -0.034)), undistorted,
          oblique_distorted_pinhole()};
}

TEST(RayGenerator, ProjectInvertsGenerateRay) {
  // A point t along the ray through pixel p projects back to p, at distance t. Tolerances:
  // the ray and the projection are each a few operations on ~1e3 px coordinates (~1e-13
  // relative); Newton's undistortion stops at a residual of 1e-13 normalized (~1e-10 px).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-20.0, 660.0), V(-20.0, 500.0), T(0.2, 1.5);
  for (const Camera& c : cameras_of_every_kind()) {
    const RayGenerator rays(c, /*ortho_start_z=*/0.5);
    for (int i = 0; i < 2000; ++i) {
      const Vec2d p(U(rng), V(rng));
      const CameraRay ray = rays.generate_ray(p.x(), p.y());
      ASSERT_TRUE(ray.ok);
      const double t = T(rng);
      const Projection back = rays.project(ray.at(t));
      ASSERT_TRUE(back.in_front);
      EXPECT_NEAR(back.pixel.x(), p.x(), 1e-8) << c.index() << " " << p.transpose();
      EXPECT_NEAR(back.pixel.y(), p.y(), 1e-8) << c.index() << " " << p.transpose();
      EXPECT_NEAR(back.distance, t, 1e-12);
      EXPECT_GT(back.depth, 0.0);
      EXPECT_LE(back.depth, back.distance + 1e-15);
    }
  }
}

TEST(RayGenerator, OrthographicDepthIsMeasuredFromTheRayStart) {
  const RayGenerator rays(OrthographicTopDown::from_pixels_per_mm(64, 48, 1.0, Vec2d(0, 0)), 0.25);
  const Projection below = rays.project(Vec3d(0.001, 0.002, 0.05));
  EXPECT_DOUBLE_EQ(below.depth, 0.2);
  EXPECT_DOUBLE_EQ(below.distance, 0.2);
  EXPECT_TRUE(below.in_front);
  // The orthographic camera sees every height: above the ray start is not "behind" it.
  EXPECT_TRUE(rays.project(Vec3d(0, 0, 1.0)).in_front);
}

TEST(Crop, TheCroppedCameraIsTheFullCameraShiftedByTheWindowCorner) {
  // Cropped pixel (u, v) is full pixel (u + x, v + y), both ways: rays and projections.
  const PixelWindow window{37, 21, 101, 64};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0.0, 100.0), V(0.0, 63.0);
  for (const Camera& full : cameras_of_every_kind()) {
    const Camera cropped = crop(full, window);
    EXPECT_EQ(camera_width(cropped), 101);
    EXPECT_EQ(camera_height(cropped), 64);
    const RayGenerator full_rays(full, 0.5), cropped_rays(cropped, 0.5);
    for (int i = 0; i < 500; ++i) {
      const double u = U(rng), v = V(rng);
      const CameraRay a = cropped_rays.generate_ray(u, v), b = full_rays.generate_ray(u + window.x, v + window.y);
      EXPECT_LT((a.origin - b.origin).norm(), 1e-12);
      EXPECT_LT((a.direction - b.direction).norm(), 1e-12);
      const Vec3d p = b.at(0.7);
      const Vec2d shift(window.x, window.y);
      EXPECT_LT((cropped_rays.project(p).pixel + shift - full_rays.project(p).pixel).norm(), 1e-9);
    }
  }
}

TEST(Crop, AWindowOfTheWholeImageIsTheSameCamera) {
  for (const Camera& c : cameras_of_every_kind()) {
    const Camera same = crop(c, PixelWindow{0, 0, camera_width(c), camera_height(c)});
    EXPECT_TRUE(same == c);
  }
}

TEST(PixelWindow, CoversTheBoxInWholePixelsClampedToTheImage) {
  const Camera c = OrthographicTopDown::from_pixels_per_mm(64, 48, 1.0, Vec2d(0, 0));
  const PixelWindow inside = pixel_window(c, Vec2d(3.2, 4.9), Vec2d(10.1, 7.0));
  EXPECT_EQ(inside.x, 3);
  EXPECT_EQ(inside.y, 4);
  EXPECT_EQ(inside.width, 8);   // columns 3..10
  EXPECT_EQ(inside.height, 3);  // rows 4..6 (7.0 is the end, exactly)
  const PixelWindow clamped = pixel_window(c, Vec2d(-5.5, -1.0), Vec2d(80.0, 60.0));
  EXPECT_EQ(clamped.x, 0);
  EXPECT_EQ(clamped.y, 0);
  EXPECT_EQ(clamped.width, 64);
  EXPECT_EQ(clamped.height, 48);
  // A box beside the image still gives a window inside it, at least one pixel.
  const PixelWindow outside = pixel_window(c, Vec2d(100.0, 100.0), Vec2d(90.0, 90.0));
  EXPECT_EQ(outside.x, 63);
  EXPECT_EQ(outside.y, 47);
  EXPECT_EQ(outside.width, 1);
  EXPECT_EQ(outside.height, 1);
}

TEST(GroundUnitsPerPixel, OrthographicAndPinholeLookingDown) {
  EXPECT_DOUBLE_EQ(ground_units_per_pixel(OrthographicTopDown::from_pixels_per_mm(64, 48, 4.0, Vec2d(0, 0))),
                   1.0 / 4000.0);
  // 0.8 m above the ground with f = 1000 px: 0.8 mm per pixel.
  const Camera down = Pinhole::look_at(640, 480, 1000.0, Vec3d(0.1, 0.2, 0.8), Vec3d(0.1, 0.2, 0.0));
  EXPECT_NEAR(ground_units_per_pixel(down), 0.8 / 1000.0, 1e-15);
  // Looking up, the optical axis never meets the ground.
  const Camera up = Pinhole::look_at(640, 480, 1000.0, Vec3d(0, 0, 0.8), Vec3d(0, 0, 2.0));
  EXPECT_EQ(ground_units_per_pixel(up), 0.0);
}

TEST(CameraYaml, ParsesBothForms) {
  const Camera a = parse_camera(
      YAML::Load("{type: orthographic, width: 2048, height: 1536, pixels_per_mm: 10, centre_m: [0.01, 0]}"), "a");
  const auto& o = std::get<OrthographicTopDown>(a);
  EXPECT_EQ(o.width, 2048);
  EXPECT_DOUBLE_EQ(o.pixels_per_unit, 10000.0);
  EXPECT_DOUBLE_EQ(o.centre.x(), 0.01);
  const Camera b = parse_camera(YAML::Load("{type: pinhole, width: 640, height: 480, fx: 500, cx: 320, "
                                           "distortion: [-0.1, 0.01, 0, 0], eye: [0, 0, 2], target: [0, 0, 0]}"),
                                "b");
  const auto& p = std::get<Pinhole>(b);
  EXPECT_DOUBLE_EQ(p.fy, 500.0);  // defaults to fx
  EXPECT_DOUBLE_EQ(p.cx, 320.0);
  EXPECT_DOUBLE_EQ(p.cy, 239.5);  // defaults to the image centre
  EXPECT_DOUBLE_EQ(p.distortion[0], -0.1);
  EXPECT_DOUBLE_EQ(p.distortion[4], 0.0);
}

TEST(CameraYaml, ErrorsNameTheSourceAndTheKey) {
  const std::string unknown = message_of("{type: orthographic, width: 10, height: 10, pixels_per_mm: 1, colour: red}");
  EXPECT_EQ(unknown,
            "cams.yaml:1: camera: unknown key 'colour' (allowed: centre, centre_m, height, pixels_per_mm, "
            "pixels_per_unit, type, width)");

  const std::string missing = message_of("{type: pinhole, height: 480, fx: 500, eye: [0, 0, 1], target: [0, 0, 0]}");
  EXPECT_EQ(missing, "cams.yaml:1: camera: missing key 'width'");

  const std::string negative =
      message_of("{type: pinhole, width: 640, height: 480, fx: -500, eye: [0, 0, 1], target: [0, 0, 0]}");
  EXPECT_EQ(negative, "cams.yaml:1: 'camera.fx' must be > 0 (got -500)");

  const std::string bad_fy =
      message_of("{type: pinhole, width: 640, height: 480, fx: 500, fy: 0, eye: [0, 0, 1], target: [0, 0, 0]}");
  EXPECT_EQ(bad_fy, "cams.yaml:1: 'camera.fy' must be > 0 (got 0)");

  const std::string bad_type = message_of("{type: fisheye, width: 640, height: 480}");
  EXPECT_EQ(bad_type, "cams.yaml:1: 'camera.type' must be one of orthographic, pinhole (got 'fisheye')");

  const std::string bad_width = message_of("{type: orthographic, width: 10.5, height: 10, pixels_per_mm: 1}");
  EXPECT_EQ(bad_width, "cams.yaml:1: 'camera.width' must be an integer (got '10.5')");

  const std::string not_rigid = message_of(
      "{type: pinhole, width: 64, height: 48, fx: 50, camera_from_world: "
      "[[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}");
  EXPECT_NE(not_rigid.find("'camera_from_world'"), std::string::npos) << not_rigid;

  const std::string short_dist = message_of(
      "{type: pinhole, width: 64, height: 48, fx: 50, distortion: [0.1], eye: [0, 0, 1], target: [0, 0, 0]}");
  EXPECT_EQ(short_dist, "cams.yaml:1: 'camera.distortion' must have 4 to 5 numbers (got 1)");

  // On its own line in a block mapping, each value names its own line.
  EXPECT_EQ(message_of("type: pinhole\nwidth: 64\nheight: 0\nfx: 50\n"),
            "cams.yaml:3: 'camera.height' must be in [1, 65536] (got 0)");
}

}  // namespace
}  // namespace meltlab::render
