// Cameras (camera.h): projection conventions, agreement with OpenCV, YAML parsing and the
// JSON round trip.

#include <meltlab/render/camera.h>
#include <meltlab/core/error.h>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <yaml-cpp/yaml.h>

#include <random>

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
  auto [p0, ok0] = project(c, Vec3d(0.01, -0.02, 0.5));
  EXPECT_TRUE(ok0);
  EXPECT_NEAR(p0.x(), 1023.5, kOrthoTolPx);
  EXPECT_NEAR(p0.y(), 767.5, kOrthoTolPx);
  // 1 mm to +x is 10 px to the right; 1 mm to +y is 10 px up (smaller v).
  auto [p1, ok1] = project(c, Vec3d(0.011, -0.02, 0.0));
  EXPECT_NEAR(p1.x(), 1033.5, kOrthoTolPx);
  EXPECT_NEAR(p1.y(), 767.5, kOrthoTolPx);
  auto [p2, ok2] = project(c, Vec3d(0.01, -0.019, 0.0));
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
  const cv::Mat dist = (cv::Mat_<double>(1, 5) << p.distortion[0], p.distortion[1], p.distortion[2],
                        p.distortion[3], p.distortion[4]);
  std::vector<cv::Point2d> img;
  cv::projectPoints(pts, rvec, tvec, K, dist, img);
  const Camera c = p;
  for (std::size_t i = 0; i < world.size(); ++i) {
    auto [uv, ok] = project(c, world[i]);
    ASSERT_TRUE(ok);
    // Rodrigues round-trips R to ~1e-15, i.e. ~1e-12 px here: inside kProjectTolPx.
    EXPECT_NEAR(uv.x(), img[i].x, kProjectTolPx) << i;
    EXPECT_NEAR(uv.y(), img[i].y, kProjectTolPx) << i;
  }
}

TEST(Pinhole, PointBehindTheCameraIsFlagged) {
  const Camera c = Pinhole::look_at(640, 480, 500.0, Vec3d(0, 0, 1), Vec3d(0, 0, 0));
  EXPECT_TRUE(project(c, Vec3d(0, 0, 0)).second);
  EXPECT_FALSE(project(c, Vec3d(0, 0, 2)).second);
  EXPECT_FALSE(project(c, Vec3d(0.1, 0, 1)).second);  // in the camera plane (z_camera = 0)
}

TEST(Pinhole, LookAtPutsTheTargetAtThePrincipalPointWithUpUp) {
  for (const Vec3d& eye : {Vec3d(0, 0, 3), Vec3d(1, -2, 0.5), Vec3d(-0.3, 0.2, -4)}) {
    const Vec3d target(0.1, 0.2, 0.05);
    const Pinhole p = Pinhole::look_at(2048, 1536, 1800.0, eye, target, Vec3d(0, 0, 1) + Vec3d(0, 1, 0));
    const Camera c = p;
    auto [uv, ok] = project(c, target);
    ASSERT_TRUE(ok);
    // Rotation + division by the distance: round-off of ~1e3 px coordinates.
    EXPECT_NEAR(uv.x(), 1023.5, 1e-9);
    EXPECT_NEAR(uv.y(), 767.5, 1e-9);
    // The rotation is proper and orthonormal.
    const Eigen::Matrix3d R = p.camera_from_world.linear();
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  }
  // Looking straight down with up = +y: world +x is image right, world +y is image up.
  const Camera down = Pinhole::look_at(640, 480, 500.0, Vec3d(0, 0, 2), Vec3d(0, 0, 0));
  const Vec2d c0 = project(down, Vec3d(0, 0, 0)).first;
  const Vec2d cx = project(down, Vec3d(0.1, 0, 0)).first;
  const Vec2d cy = project(down, Vec3d(0, 0.1, 0)).first;
  EXPECT_GT(cx.x(), c0.x() + 20);
  EXPECT_NEAR(cx.y(), c0.y(), 1e-9);
  EXPECT_LT(cy.y(), c0.y() - 20);
  EXPECT_NEAR(cy.x(), c0.x(), 1e-9);
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

TEST(CameraYaml, DescribeRoundTripsExactly) {
  Pinhole p = Pinhole::look_at(1600, 1200, 1234.5678, Vec3d(0.31, -0.47, 1.93), Vec3d(0.01, 0.02, 0.0));
  p.fy = 1240.125;
  p.cx = 801.3;
  p.cy = 597.1;
  p.distortion = {-0.2, 0.07, 1e-3, -2e-4, 0.01};
  const std::vector<Camera> cams = {OrthographicTopDown::from_pixels_per_mm(2048, 1536, 7.3, Vec2d(0.0123, -0.0456)),
                                    p, Pinhole{}};
  for (const Camera& c : cams) {
    const std::string text = describe_camera_json(c);
    const Camera back = parse_camera(YAML::Load(text), "round-trip");
    ASSERT_EQ(back.index(), c.index()) << text;
    EXPECT_EQ(describe_camera_json(back), text);
    if (const auto* o = std::get_if<OrthographicTopDown>(&c)) {
      const auto& q = std::get<OrthographicTopDown>(back);
      EXPECT_EQ(q.pixels_per_unit, o->pixels_per_unit);  // bitwise: shortest round-trip decimals
      EXPECT_EQ(q.centre, o->centre);
      EXPECT_EQ(q.width, o->width);
      EXPECT_EQ(q.height, o->height);
    } else {
      const auto& a = std::get<Pinhole>(c);
      const auto& q = std::get<Pinhole>(back);
      EXPECT_EQ(q.fx, a.fx);
      EXPECT_EQ(q.fy, a.fy);
      EXPECT_EQ(q.cx, a.cx);
      EXPECT_EQ(q.cy, a.cy);
      EXPECT_EQ(q.distortion, a.distortion);
      EXPECT_EQ(q.camera_from_world.matrix(), a.camera_from_world.matrix());
    }
  }
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
