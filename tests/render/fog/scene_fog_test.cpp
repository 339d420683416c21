// Seed 002's fog in the ice renderer (fog/scene_fog.h, integrator/ice_surface.h): the scene's
// `fog:` section, the per-pixel fog pass against the per-ray model, and the renderer with fog
// against the renderer without.

#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/render/fog/scene_fog.h>
#include <meltlab/render/integrator/ice_surface.h>
#include <meltlab/render/render_scene.h>
#include <meltlab/render/texture/assets.h>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <unistd.h>

namespace meltlab::render::fog {
namespace {

constexpr double kDeg = std::numbers::pi / 180;
// Float image storage (7 digits) of a double computation.
constexpr double kPixelTol = 1e-5;

const char* kFogScene =
    "{width: 48, height: 36, fog: {kt: 0.4, far: 8, spotlights: [{position: [-1, -1, 3], target: [0, 0, 0.3], "
    "half_angle_deg: 25, intensity: 12, rings: [{half_angle_deg: 10, intensity: 2}]}], "
    "table: {n: 32, function: F, u_warp: none, v_warp: smooth, v_interp: index}, view_attenuation: source_omit, "
    "specular_args: source}}";

std::string message(const std::string& y) {
  try {
    parse_render_scene(YAML::Load(y), "scene.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SceneFog, ParsesEveryKeyAndRefusesBadOnes) {
  const RenderScene s = parse_render_scene(YAML::Load(kFogScene), "scene.yaml");
  ASSERT_TRUE(s.fog);
  const SceneFog& f = *s.fog;
  EXPECT_EQ(f.medium.kt, 0.4);
  EXPECT_EQ(f.far, 8);
  ASSERT_EQ(f.spotlights.size(), 1u);
  const Spotlight& l = f.spotlights[0];
  EXPECT_LT((l.axis - (Vec3(0, 0, 0.3) - Vec3(-1, -1, 3)).normalized()).norm(), 1e-15);
  ASSERT_EQ(l.profile.size(), 2u);  // the ring, then the outer cone
  EXPECT_NEAR(l.profile[0].half_angle_rad, 10 * kDeg, 1e-15);
  EXPECT_EQ(l.profile[0].intensity, 2);
  EXPECT_NEAR(l.profile[1].half_angle_rad, 25 * kDeg, 1e-15);
  EXPECT_EQ(l.profile[1].intensity, 1);
  EXPECT_EQ(f.tables.n, 32);
  EXPECT_EQ(f.function, TableFunction::kF);
  EXPECT_EQ(f.tables.u_warp, AxisWarp::kNone);
  EXPECT_EQ(f.tables.v_warp, AxisWarp::kSmooth);
  EXPECT_EQ(f.tables.v_interp, InterpSpace::kIndex);
  EXPECT_EQ(f.model.view_attenuation, ViewAttenuation::kSourceOmit);
  EXPECT_EQ(f.model.specular_args, SpecularArgs::kSource);
  EXPECT_FALSE(parse_render_scene(YAML::Load("{}"), "scene.yaml").fog);
  // Defaults: the harness's table.
  const RenderScene d =
      parse_render_scene(YAML::Load("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}]}}"), "scene.yaml");
  EXPECT_EQ(d.fog->function, TableFunction::kH);
  EXPECT_EQ(d.fog->tables.u_warp, AxisWarp::kCbrt);
  EXPECT_EQ(d.fog->tables.v_warp, AxisWarp::kSqrtHi);
  EXPECT_EQ(d.fog->tables.v_interp, InterpSpace::kValue);
  EXPECT_EQ(d.fog->model.view_attenuation, ViewAttenuation::kApply);
  // A point light (S3's comparison): no cone, intensity 1 in every direction.
  const RenderScene p = parse_render_scene(
      YAML::Load("{fog: {spotlights: [{kind: point, position: [0, 0, 4], intensity: 30}]}}"), "scene.yaml");
  ASSERT_EQ(p.fog->spotlights.size(), 1u);
  EXPECT_EQ(p.fog->spotlights[0].kind, LightKind::kPoint);
  EXPECT_TRUE(p.fog->spotlights[0].profile.empty());
  EXPECT_EQ(p.fog->spotlights[0].intensity, 30);
  EXPECT_EQ(p.fog->spotlights[0].intensity_at(Vec3(5, -3, 0)), 1.0);
  EXPECT_NE(message("{fog: {spotlights: [{kind: point, position: [0, 0, 3], target: [0, 0, 0]}]}}").find("point"),
            std::string::npos);
  EXPECT_NE(message("{fog: {spotlights: [{kind: lamp, position: [0, 0, 3], target: [0, 0, 0]}]}}").find(".kind'"),
            std::string::npos);
  EXPECT_NE(message("{fog: {kt: 0.1}}").find("'spotlights'"), std::string::npos) << message("{fog: {kt: 0.1}}");
  EXPECT_NE(message("{fog: {kt: -1, spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}]}}").find("'fog.kt'"),
            std::string::npos);
  EXPECT_NE(message("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 3]}]}}").find("'target'"),
            std::string::npos);
  EXPECT_NE(message("{fog: {spotlights: [{position: [0, 0, 3]}]}}").find("'target'"), std::string::npos);
  EXPECT_NE(message("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0], half_angle_deg: 95}]}}")
                .find("half_angle_deg"),
            std::string::npos);
  EXPECT_NE(message("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0], half_angle_deg: 20, "
                    "rings: [{half_angle_deg: 30}]}]}}")
                .find("must exceed every ring"),
            std::string::npos);
  EXPECT_NE(
      message("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0], spin: 1}]}}").find("unknown key 'spin'"),
      std::string::npos);
  EXPECT_NE(message("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}], table: {function: G}}}")
                .find("'fog.table.function' must be one of"),
            std::string::npos)
      << message("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}], table: {function: G}}}");
  EXPECT_NE(
      message("{fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}], fogg: 1}}").find("unknown key 'fogg'"),
      std::string::npos);
}

TEST(SceneFog, ApplyIsTheAttenuatedPixelPlusThePerRayModel) {
  SceneFog f = parse_render_scene(YAML::Load(kFogScene), "scene.yaml").fog.value();
  f.model.view_attenuation = ViewAttenuation::kApply;
  const FogShader shader(f, {60, 30});
  const FogMaterial mat = FogShader::material(0.25, 0.6, 60);
  EXPECT_EQ(mat.n, 60);
  TableOptions to = f.tables;
  const FogTableSet t = build_fog_tables(to, f.function, 60);
  const FogFunctions fn = t.functions();
  const Vec3 o(0, -4, 1.5), p(0.1, 0.2, 0.4);
  const Vec3 d = (p - o).normalized();
  const double m = (p - o).norm();
  const SurfaceHit hit{p, Vec3(0, -1, 0.3).normalized(), &mat};
  const Rgb shaded(0.2, 0.3, 0.4);
  const Rgb got = shader.apply(shaded, o, d, m, &hit);
  const Rgb want =
      std::exp(-f.medium.kt * m) * shaded + fog_radiance(o, d, m, &hit, f.spotlights, f.medium, fn, f.model);
  EXPECT_LT((got - want).norm(), 1e-12 * want.norm());
  EXPECT_GT((want - std::exp(-f.medium.kt * m) * shaded).minCoeff(), 0.0);  // the spotlight adds light here
  // Nothing hit: the ray ends at `far`.
  const Rgb sky = shader.apply(shaded, o, Vec3(0, 0, 1), 0.0, nullptr);
  const Rgb sky_want = std::exp(-f.medium.kt * f.far) * shaded +
                       fog_radiance(o, Vec3(0, 0, 1), f.far, nullptr, f.spotlights, f.medium, fn, f.model);
  EXPECT_LT((sky - sky_want).norm(), 1e-12 * sky_want.norm());
  // A Phong exponent the shader has no G_n table for is a caller's bug.
  const FogMaterial other = FogShader::material(0.25, 0.6, 45);
  const SurfaceHit hit45{p, hit.normal, &other};
  EXPECT_THROW(shader.apply(shaded, o, d, m, &hit45), InvariantError);
}

TEST(SceneFog, RendererWithADarkSpotlightIsThePlainRendererAttenuated) {
  // A ground and an ice sphere under the default lights; the fog's spotlight has intensity 0, so
  // the fog pass only attenuates: at k_t = 0 the image is the plain one exactly, at k_t > 0 every
  // pixel is the plain pixel times e^{-k_t m} (m <= far) -- never brighter, the sky by e^{-k_t far}.
  const char* base = "{width: 40, height: 30, ground: {z: 0}}";
  RenderScene plain = parse_render_scene(YAML::Load(base), "scene.yaml");
  auto fogged = [&](double kt) {
    RenderScene s = plain;
    SceneFog f;
    f.medium.kt = kt;
    f.far = 50;
    Spotlight l;
    l.position = Vec3(0, 0, 5);
    l.axis = Vec3(0, 0, -1);
    l.intensity = 0;
    f.spotlights = {l};
    f.tables.n = 16;
    s.fog = f;
    return s;
  };
  FogScene only_ball;
  only_ball.spheres = {AnalyticSphere{Vec3(0, 0, 1), 0.5}};
  const sim::IndexedMesh ball = scene_mesh(only_ball, 2000);
  IceRenderer a(plain), b(fogged(0.0)), c(fogged(0.2));
  a.set_mesh(ball);
  b.set_mesh(ball);
  c.set_mesh(ball);
  const RgbImage ia = a.render(), ib = b.render(), ic = c.render();
  int darker = 0;
  for (int j = 0; j < 30; ++j)
    for (int i = 0; i < 40; ++i) {
      const Rgb pa = rgb_at(ia, i, j), pb = rgb_at(ib, i, j), pc = rgb_at(ic, i, j);
      EXPECT_EQ(pa, pb) << i << " " << j;
      for (int k = 0; k < 3; ++k) {
        EXPECT_LE(pc[k], pa[k] + kPixelTol) << i << " " << j;
        EXPECT_GE(pc[k], std::exp(-0.2 * 50) * pa[k] - kPixelTol) << i << " " << j;
      }
      if (pc.sum() < 0.99 * pa.sum()) ++darker;
    }
  EXPECT_GT(darker, 40 * 30 / 2);
}

TEST(SceneFog, TheFogsSurfaceTermsOnTheGroundTakeTheTexturesColour) {
  // A ground textured in one colour (1, 0.5, 0.25), no specular (cs 0), a bright white spotlight
  // in almost clear air (k_t 1e-6: the airlight is ~1e-6 of the direct term). The fog pass adds,
  // on every lit ground pixel, the spotlight's direct Phong term times the diffuse colour, so the
  // added light must have the texture's channel ratios; with a white diffuse colour (the pass
  // before it read the texture) it would be grey. For both texture filters (bilinear and the
  // mipmap footprints, which the fog pass now traces too).
  const auto dir = std::filesystem::temp_directory_path() / ("meltlab_fog_tex_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  ImageF tex(8, 8, 3);
  for (int j = 0; j < 8; ++j)
    for (int i = 0; i < 8; ++i) tex.at(i, j, 0) = 1.0f, tex.at(i, j, 1) = 0.5f, tex.at(i, j, 2) = 0.25f;
  const auto tex_file = dir / "orange.exr";
  write_image(tex_file, tex);
  for (const char* filter : {"bilinear", "mipmap"}) {
    const std::string base = std::string("{width: 40, height: 30, texture_filter: ") + filter +
                             ", camera: {type: pinhole, width: 40, height: 30, eye: [0, -4, 3], target: [0, 0, 0], up: "
                             "[0, 0, 1], fov_deg: 50}, "
                             "ground: {z: 0, cs: 0, tile: 1, texture: " +
                             tex_file.string() + "}}";
    RenderScene plain = parse_render_scene(YAML::Load(base), (dir / "scene.yaml").string());
    RenderScene fogged = plain;
    SceneFog f;
    f.medium.kt = 1e-6;
    f.far = 50;
    Spotlight l;
    l.position = Vec3(0, 0, 3);
    l.axis = Vec3(0, 0, -1);
    l.profile = {ConeStep{40 * kDeg, 1.0}};
    l.intensity = 5;
    f.spotlights = {l};
    f.tables.n = 32;
    fogged.fog = f;
    FogScene tiny;
    tiny.spheres = {AnalyticSphere{Vec3(3, 3, 0.2), 0.1}};  // out of the way: the ground is what is seen
    const sim::IndexedMesh mesh = scene_mesh(tiny, 200);
    IceRenderer a(plain), b(fogged);
    a.set_mesh(mesh);
    b.set_mesh(mesh);
    const RgbImage ia = a.render(), ib = b.render();
    int lit = 0;
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 40; ++i) {
        const Rgb added = rgb_at(ib, i, j) - rgb_at(ia, i, j);
        if (added[0] < 0.05) continue;  // not in the spotlight (or not the ground)
        ++lit;
        // Float image storage (kPixelTol per channel) and the ~1e-6 airlight.
        EXPECT_NEAR(added[1] / added[0], 0.5, 1e-3) << filter << " " << i << " " << j;
        EXPECT_NEAR(added[2] / added[0], 0.25, 1e-3) << filter << " " << i << " " << j;
      }
    EXPECT_GT(lit, 40 * 30 / 10) << filter << ": the spotlight must light the ground, or the test says nothing";
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace meltlab::render::fog
