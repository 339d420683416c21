// Cameras and render scenes written as JSON at the edge (experiments/render_json.h): a camera
// written and read back with render::parse_camera is the same camera, bit for bit (observation
// manifests carry their camera this way); a scene record names its image files.
#include <meltlab/experiments/render_json.h>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <vector>

namespace meltlab::experiments {
namespace {

using render::Camera, render::OrthographicTopDown, render::Pinhole, render::parse_camera;
using Vec2d = Eigen::Vector2d;
using Vec3d = Eigen::Vector3d;

TEST(CameraJson, ReadsBackAsTheSameCameraBitForBit) {
  Pinhole p = Pinhole::look_at(1600, 1200, 1234.5678, Vec3d(0.31, -0.47, 1.93), Vec3d(0.01, 0.02, 0.0));
  p.fy = 1240.125;
  p.cx = 801.3;
  p.cy = 597.1;
  p.distortion = {-0.2, 0.07, 1e-3, -2e-4, 0.01};
  const std::vector<Camera> cams = {OrthographicTopDown::from_pixels_per_mm(2048, 1536, 7.3, Vec2d(0.0123, -0.0456)), p,
                                    Pinhole{}};
  for (const Camera& c : cams) {
    const std::string text = camera_json(c).dump();
    const Camera back = parse_camera(YAML::Load(text), "round-trip");
    ASSERT_EQ(back.index(), c.index()) << text;
    EXPECT_EQ(camera_json(back).dump(), text);
    EXPECT_TRUE(back == c);
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

TEST(RenderSceneJson, NamesTheFilesAndTheFallbacks) {
  render::RenderScene scene;
  scene.environment.file = "/data/sky.exr";
  const nlohmann::json j = render_scene_json(scene);
  EXPECT_EQ(j["environment"]["source"], "/data/sky.exr");
  EXPECT_EQ(j["ground"]["texture_source"], "procedural");
  EXPECT_EQ(j["ice"]["texture_source"], "procedural milky ice");
  EXPECT_EQ(j["camera"], "auto");
  EXPECT_EQ(j["lights"].size(), scene.lights.size());
  EXPECT_EQ(j["ice"]["eta"].get<double>(), scene.ice.eta);
  scene.camera = Pinhole{};
  EXPECT_EQ(render_scene_json(scene)["camera"], camera_json(*scene.camera));
}

}  // namespace
}  // namespace meltlab::experiments
