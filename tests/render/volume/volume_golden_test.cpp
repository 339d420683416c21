// Golden images: every example scene of experiments/configs/volume (one per optical model) at
// 24 x 24 pixels and 32 samples per ray, against PNGs in tests/assets/volume that were looked at by
// eye when they were made (MELTLAB_UPDATE_GOLDEN=1 rewrites them; look at them before committing).
// A regression guard for what the closed-form tests do not pin down: the scenes, the generators,
// the camera and the composite as a user sees them.

#include <meltlab/core/image.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/volume/volume_scene.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace meltlab::render {
namespace {

namespace fs = std::filesystem;

fs::path assets() {
  const char* dir = std::getenv("MELTLAB_TEST_DATA");
  return dir ? fs::path(dir) : fs::path("tests/assets");
}

// The PNG stores round(255 v): a pixel may move by one level where a value sits on a rounding
// boundary and the arithmetic changes in the last bits (another compiler, another SIMD width).
constexpr double kLevels = 1.0 / 255.0;

class VolumeGolden : public ::testing::TestWithParam<std::string> {};

TEST_P(VolumeGolden, ExampleSceneMatchesItsGoldenImage) {
  const std::string name = GetParam();
  VolumeScene scene = read_volume_scene(assets() / "../../experiments/configs/volume" / (name + ".yaml"));
  auto pin = std::get<Pinhole>(scene.camera);
  const double s = 24.0 / pin.width;
  pin.fx *= s, pin.fy *= s, pin.cx = (pin.cx + 0.5) * s - 0.5, pin.cy = (pin.cy + 0.5) * s - 0.5;
  pin.width = pin.height = 24;
  scene.camera = pin;
  scene.settings.samples = 32;
  const Volume v = load_scene_volume(scene);
  const ImageF colour = composite_over(render_volume(v, scene.camera, scene.settings), scene.settings.background);
  ImageF png(24, 24, 3);
  for (std::size_t i = 0; i < png.size(); ++i)
    png.values()[i] = std::clamp(float(scene.exposure) * colour.values()[i], 0.0f, 1.0f);
  const fs::path golden = assets() / "volume" / ("golden_" + name + ".png");
  if (std::getenv("MELTLAB_UPDATE_GOLDEN")) write_image(golden, png);
  const ImageF g = read_image(golden);
  ASSERT_EQ(g.width(), 24);
  ASSERT_EQ(g.channels(), 3);
  int off = 0;
  for (std::size_t i = 0; i < png.size(); ++i) {
    const double d = std::abs(double(png.values()[i]) - double(g.values()[i]));
    EXPECT_LE(d, 1.01 * kLevels) << name << " value " << i;
    off += d > 0.5 * kLevels;
  }
  EXPECT_LE(off, 24) << name << ": values off by one level";  // a few boundary cases at most
}

INSTANTIATE_TEST_SUITE_P(Scenes, VolumeGolden,
                         ::testing::Values("absorption_cloud", "emission_flame", "ea_fireball", "hg", "hg_attenuated"));

}  // namespace
}  // namespace meltlab::render
