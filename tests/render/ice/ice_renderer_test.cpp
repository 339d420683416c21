// The ice/liquid ray tracer (integrator/ice_surface.h): analytic pixels of the ground (Eq. 2.13) and the
// wet ground (Eq. 7.17), the Fresnel-weighted reflection and refraction of the ice (Eq. 6.11),
// dispersion, the physically based reference on a sphere (Beer absorption), skipping, the BVH
// refit, and small reference images.

#include <meltlab/datasets/procedural.h>
#include <meltlab/render/embree/mesh_bvh.h>
#include <meltlab/render/integrator/ice_surface.h>
#include <meltlab/render/material/optics.h>
#include <meltlab/render/texture/assets.h>
#include <meltlab/core/error.h>

#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

namespace meltlab::render {
namespace {

using Eigen::Vector3d;

// Float image storage (7 digits) of a double computation.
constexpr double kPixelTol = 1e-5;
// A faceted icosphere (5120 triangles): the interpolated normal near the pole is within
// ~1° of the true one and the chord path within ~0.1 % of the diameter.
constexpr double kSphereRelTol = 0.02;
// Reference images: 8-bit PNGs; allow a mean of 1 level and a few isolated pixels (a silhouette
// pixel may flip between ice and ground with float rounding in another build).
constexpr double kRefMeanTol = 1.0 / 255.0;
constexpr double kRefBadPixelFraction = 0.01;

RenderScene top_down_scene(int w, int h, double ppu) {
  RenderScene s;
  OrthographicTopDown cam;
  cam.width = w;
  cam.height = h;
  cam.pixels_per_unit = ppu;
  s.camera = cam;
  s.lights = {DirectionalLight{Vector3d(0, 0, 1), Rgb(1, 1, 1)}};
  return s;
}

// top_down_scene over the plain Phong ground z = 0 (ca 0.2 + cd 0.5 under the vertical
// light, no specular), its texture tiled every 2 units.
RenderScene dry_ground_scene(int w, int h, double ppu) {
  RenderScene s = top_down_scene(w, h, ppu);
  s.ground.z = 0.0;
  s.ground.tile = 2.0;
  s.ground.ca = 0.2;
  s.ground.cd = 0.5;
  s.ground.cs = 0.0;
  return s;
}

sim::IndexedMesh sphere(double r, const Vector3d& c) {
  auto m = datasets::icosphere(4, r);
  for (auto& v : m.V) v += c;
  return m;
}

Rgb pixel(const RgbImage& img, int i, int j) { return rgb_at(img, i, j); }

TEST(IceRenderer, DryGroundIsPhongTimesTexture) {
  const auto s = dry_ground_scene(32, 32, 10.0);
  IceRenderer r(s);
  r.set_mesh(sphere(0.1, Vector3d(100, 100, 1)));  // far outside the view
  const RgbImage img = r.render();
  const RgbImage tex = ground_texture(256, 1);
  for (int j = 0; j < 32; j += 5)
    for (int i = 0; i < 32; i += 7) {
      const double x = (i - 15.5) / 10.0, y = -(j - 15.5) / 10.0;
      const Rgb want = 0.7 * sample_bilinear_rgb(tex, x / 2.0 * 256 - 0.5, y / 2.0 * 256 - 0.5, ImageWrap::kRepeat,
                                                 ImageWrap::kRepeat);
      EXPECT_NEAR((pixel(img, i, j) - want).norm(), 0.0, kPixelTol) << i << "," << j;
    }
}

TEST(IceRenderer, WetGroundIsDarkenedByTheExponentAndTiltedAtTheRim) {
  auto s = dry_ground_scene(40, 40, 10.0);  // 4 x 4 units
  s.ground.cr = 0.0;
  s.ground.d = 0.0;
  IceRenderer r(s);
  r.set_mesh(sphere(0.1, Vector3d(100, 100, 1)));
  sim::LiquidMaskParams mp;
  mp.width = mp.height = 40;
  mp.texel_size = 0.1;
  mp.origin = Eigen::Vector2d(-2, -2);
  mp.threshold = 0.5f;
  sim::LiquidMask mask(mp);
  for (int j = 10; j < 30; ++j)
    for (int i = 10; i < 30; ++i) mask.values()[static_cast<std::size_t>(j) * 40 + i] = 1.0f;
  const RgbImage dry = r.render();
  r.set_liquid(&mask);
  ASSERT_TRUE(r.plan().liquid);
  const RgbImage wet = r.render();
  // Inside the puddle, away from the rim: (0.7 tdiff)^(1 + 0.6).
  for (int k : {15, 20, 24}) {
    const Rgb d = pixel(dry, k, k), w = pixel(wet, k, k);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(w[c], std::pow(d[c], 1.6), kPixelTol) << k;
  }
  // Outside: unchanged.
  EXPECT_NEAR((pixel(wet, 3, 3) - pixel(dry, 3, 3)).norm(), 0.0, kPixelTol);
  // On the rim the normal tilts away from the light (straight up), so it is darker than the
  // darkened interior formula alone gives.
  const int rim_i = 10, rim_j = 20;  // texel column 10 is the puddle's left edge (x = -1)
  const Rgb d = pixel(dry, rim_i, rim_j), w = pixel(wet, rim_i, rim_j);
  const double tilt_cos = 1.0 / std::sqrt(1.0 + 0.49);
  const Rgb want = ((0.2 + 0.5 * tilt_cos) / 0.7 * d).array().pow(1.6).matrix();
  EXPECT_NEAR((w - want).norm(), 0.0, 1e-4) << w.transpose() << " vs " << want.transpose();
}

TEST(IceRenderer, FilmOffsetShiftsTheTextureAgainstTheViewDirection) {
  // An oblique pinhole view of a puddle covering the whole view: every ground pixel is wet,
  // with cs = cr = tilt = 0 its value is (0.7·tdiff(s - d·Vx, t - d·Vy))^1.6 (Eq. 7.10-7.11).
  RenderScene s;
  s.camera = Pinhole::look_at(24, 18, 30.0, Vector3d(0.0, -3.0, 2.0), Vector3d(0, 0, 0), Vector3d(0, 0, 1));
  s.lights = {DirectionalLight{Vector3d(0, 0, 1), Rgb(1, 1, 1)}};
  s.ground.z = 0.0;
  s.ground.tile = 1.0;
  s.ground.ca = 0.2;
  s.ground.cd = 0.5;
  s.ground.cs = s.ground.cr = s.ground.tilt_s = s.ground.tilt_t = 0.0;
  s.ground.d = 0.1;
  IceRenderer r(s);
  r.set_mesh(sphere(0.05, Vector3d(100, 100, 1)));
  sim::LiquidMaskParams mp;
  mp.width = mp.height = 64;
  mp.texel_size = 1.0;
  mp.origin = Eigen::Vector2d(-32, -32);
  sim::LiquidMask mask(mp);
  for (auto& v : mask.values()) v = 1.0f;
  r.set_liquid(&mask);
  ASSERT_TRUE(r.plan().liquid_offset);
  const RgbImage img = r.render();
  const auto& cam = std::get<Pinhole>(r.camera());
  const Eigen::Isometry3d world_from_camera = cam.camera_from_world.inverse();
  const RgbImage tex = ground_texture(256, 1);
  int checked = 0, shifted = 0;
  for (int j = 9; j < 18; j += 2)  // the lower half of the image looks at the ground
    for (int i = 0; i < 24; i += 3) {
      const Vector3d o = world_from_camera.translation();
      const Vector3d d =
          (world_from_camera.linear() * Vector3d((i - cam.cx) / cam.fx, (j - cam.cy) / cam.fy, 1)).normalized();
      ASSERT_LT(d.z(), 0);
      const Vector3d q = o + (-o.z() / d.z()) * d;
      const Vector3d V = -d;
      auto tdiff = [&](double u, double v) {
        return sample_bilinear_rgb(tex, u * 256 - 0.5, v * 256 - 0.5, ImageWrap::kRepeat, ImageWrap::kRepeat);
      };
      const Rgb want = (0.7 * tdiff(q.x() - 0.1 * V.x(), q.y() - 0.1 * V.y())).array().pow(1.6).matrix();
      const Rgb unshifted = (0.7 * tdiff(q.x(), q.y())).array().pow(1.6).matrix();
      EXPECT_NEAR((rgb_at(img, i, j) - want).norm(), 0.0, 1e-4) << i << "," << j;
      ++checked;
      shifted += (want - unshifted).norm() > 1e-3;
    }
  EXPECT_GT(checked, 20);
  EXPECT_GT(shifted, checked / 2);  // the offset is visible, so the check above has teeth
}

TEST(IceRenderer, FlatNormalMapChangesNothingAndBumpsDo) {
  // Eq. 6.12 decodes the flat map's (½, ½, 1) to the unperturbed normal.
  auto run = [](bool normal_map, double bump) {
    RenderScene s;
    s.width = 40;
    s.height = 30;
    s.ice.normal_map = normal_map;
    s.ice.normal_map_bump = bump;
    s.ground.z = 0.0;
    IceRenderer r(s);
    r.set_mesh(sphere(1.0, Vector3d(0, 0, 1)));
    return r.render();
  };
  const RgbImage plain = run(false, 0), flat = run(true, 0), bumpy = run(true, 2.0);
  double max_flat = 0, sum_bumpy = 0;
  for (std::size_t k = 0; k < plain.values().size(); ++k) {
    max_flat = std::max(max_flat, static_cast<double>(std::abs(flat.values()[k] - plain.values()[k])));
    sum_bumpy += static_cast<double>(std::abs(bumpy.values()[k] - plain.values()[k]));
  }
  EXPECT_LT(max_flat, 1e-4);
  EXPECT_GT(sum_bumpy / static_cast<double>(plain.values().size()), 1e-3);
}

TEST(IceRenderer, DryMaskIsSkippedAndGivesTheSameImage) {
  auto s = top_down_scene(24, 24, 10.0);
  IceRenderer r(s);
  r.set_mesh(sphere(0.5, Vector3d(0, 0, 0.5)));
  const RgbImage none = r.render();
  sim::LiquidMaskParams mp;
  mp.width = mp.height = 16;
  mp.texel_size = 0.2;
  mp.origin = Eigen::Vector2d(-1.6, -1.6);
  mp.threshold = 0.5f;
  sim::LiquidMask mask(mp);
  for (auto& v : mask.values()) v = 0.4f;  // below p everywhere
  r.set_liquid(&mask);
  const ShadingPlan p = r.plan();
  EXPECT_FALSE(p.liquid);
  EXPECT_NE(std::find(p.skipped.begin(), p.skipped.end(), "liquid (no texel at or above the threshold)"),
            p.skipped.end());
  const RgbImage dry = r.render();
  EXPECT_EQ(none.values(), dry.values());
}

TEST(IceRenderer, PlanSkipsZeroWeightTerms) {
  RenderScene s;
  s.ice.ct = 0;
  s.ice.cs = 0;
  IceRenderer r(s);
  const ShadingPlan p = r.plan();
  EXPECT_FALSE(p.ice_transmission);
  EXPECT_FALSE(p.dispersion);
  EXPECT_FALSE(p.ice_specular);
  EXPECT_TRUE(p.ice_reflection);
  EXPECT_TRUE(p.fresnel);
  EXPECT_FALSE(p.liquid);  // no mask
  s.ice.cr = 0;
  EXPECT_FALSE(IceRenderer(s).plan().fresnel);
}

// Ice at the top of a sphere seen straight down: N = V = +z.
struct TopOfSphere : ::testing::Test {
  RenderScene s = top_down_scene(41, 41, 20.0);
  void SetUp() override {
    s.ice.ca = s.ice.cd = s.ice.cs = 0.0;
    s.ground.z = -3.0;
    s.environment.floor_checker = 0.0;  // a uniform floor: no edge at the nadir
  }
  Rgb centre() {
    IceRenderer r(s);
    r.set_mesh(sphere(1.0, Vector3d(0, 0, 0)));
    return pixel(r.render(), 20, 20);
  }
};

TEST_F(TopOfSphere, ReflectionIsFresnelAtNormalIncidenceTimesTheZenith) {
  s.ice.ct = 0.0;
  s.ice.cr = 1.0;
  s.ice.dispersion = false;
  const Rgb got = centre();
  const Rgb zenith = sample_latlong(latlong_environment(s.environment), Vector3d(0, 0, 1));
  const double F0 = fresnel_dielectric(1.0, 1.0, kIceEta);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], F0 * zenith[c], kSphereRelTol * F0 * zenith[c]);
  // Schlick agrees at normal incidence.
  s.ice.fresnel = FresnelMode::kSchlick;
  const Rgb sch = centre();
  EXPECT_NEAR((sch - got).norm(), 0.0, kSphereRelTol * got.norm());
}

TEST_F(TopOfSphere, RefractionLooksStraightThroughAtNormalIncidence) {
  s.ice.ct = 1.0;
  s.ice.cr = 0.0;
  s.ice.dispersion = false;
  const Rgb got = centre();
  const Rgb nadir = sample_latlong(latlong_environment(s.environment), Vector3d(0, 0, -1));
  const double F0 = fresnel_dielectric(1.0, 1.0, kIceEta);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], (1 - F0) * nadir[c], kSphereRelTol * nadir[c]);
}

TEST(IceRenderer, DispersionSplitsRedAndBlueButKeepsGreen) {
  auto s = top_down_scene(48, 48, 14.0);
  s.ice.ca = s.ice.cd = s.ice.cs = 0.0;
  s.ice.cr = 0.0;
  s.ice.ct = 1.0;
  s.ice.eta = s.ice.eta_rgb[1];
  s.ground.z = -3.0;
  auto run = [&](bool dispersion) {
    s.ice.dispersion = dispersion;
    IceRenderer r(s);
    r.set_mesh(sphere(1.5, Vector3d(0, 0, 0)));
    return r.render();
  };
  const RgbImage on = run(true), off = run(false);
  int red_differs = 0, blue_differs = 0;
  for (int j = 0; j < 48; ++j)
    for (int i = 0; i < 48; ++i) {
      const Rgb a = rgb_at(on, i, j), b = rgb_at(off, i, j);
      EXPECT_EQ(a.y(), b.y()) << i << "," << j;  // the green channel is the same refraction
      red_differs += std::abs(a.x() - b.x()) > 1e-4;
      blue_differs += std::abs(a.z() - b.z()) > 1e-4;
    }
  // The three directions are ≈ 0.2° apart, so only pixels whose lookups straddle an edge of
  // the environment (window, floor square) change; there are a few of them.
  EXPECT_GT(red_differs, 3);
  EXPECT_GT(blue_differs, 3);
}

TEST(IceRenderer, PhysicalReferenceAttenuatesByBeersLaw) {
  // Straight down through the centre of a unit sphere: path 2, normal incidence at both
  // interfaces, then the ground at z = -3 straight below. Up to terms of order F0² ≈ 3e-4:
  //   I = F0·E(+z) + (1-F0)²·e^{-2σ}·G + (1-F0)²·F0·e^{-4σ}·E(+z)
  auto s = top_down_scene(41, 41, 20.0);
  s.ice.model = IceModel::kPhysical;
  s.ice.dispersion = false;
  s.ice.absorption = {0.8, 0.3, 0.05};
  s.ground.z = -3.0;
  s.ground.textured = false;  // the exit ray's ground point need not be exact
  s.ground.cs = 0.0;
  IceRenderer r(s);
  r.set_mesh(sphere(1.0, Vector3d(0, 0, 0)));
  const Rgb got = pixel(r.render(), 20, 20);
  const Rgb E = sample_latlong(latlong_environment(s.environment), Vector3d(0, 0, 1));
  const Rgb G = Rgb::Constant(s.ground.ca + s.ground.cd);
  const double F0 = fresnel_dielectric(1.0, 1.0, kIceEta);
  for (int c = 0; c < 3; ++c) {
    const double sigma = s.ice.absorption[static_cast<std::size_t>(c)];
    const double want = F0 * E[c] + (1 - F0) * (1 - F0) * std::exp(-2 * sigma) * G[c] +
                        (1 - F0) * (1 - F0) * F0 * std::exp(-4 * sigma) * E[c];
    EXPECT_NEAR(got[c], want, kSphereRelTol * want) << "channel " << c;
  }
  // More absorption, darker: the red channel (σ = 0.8) lost more than the blue one.
  EXPECT_LT(got.x() / G.x(), got.z() / G.z());
}

// White furnace: in a uniform environment of radiance L (the ground made to return L too), a
// clear (non-absorbing) dielectric must look exactly like its surroundings — every Fresnel
// split (reflect F, transmit 1 - F, total internal reflection) must conserve the weight.
TEST(IceRenderer, WhiteFurnaceConservesEnergy) {
  constexpr double L = 0.7;
  auto run = [&](IceModel model, bool dispersion, FresnelMode mode, TextureFilter filter) {
    RenderScene s;
    s.texture_filter = filter;
    s.width = 48;
    s.height = 36;
    s.environment.constant = L;
    s.ice.model = model;
    s.ice.dispersion = dispersion;
    s.ice.fresnel = mode;
    s.ice.ca = s.ice.cd = s.ice.cs = 0.0;
    s.ice.cr = s.ice.ct = 1.0;
    s.ice.absorption = {0, 0, 0};
    s.ice.max_internal_bounces = 64;
    s.ground = GroundMaterial{};
    s.ground.z = 0.0;
    s.ground.textured = false;
    s.ground.ca = L;
    s.ground.cd = s.ground.cs = 0.0;
    IceRenderer r(s);
    auto m = sphere(1.0, Vector3d(0, 0, 1.2));
    for (auto& v : m.V) v.x() *= 1.3;  // an ellipsoid: oblique exits, some total internal reflection
    r.set_mesh(m);
    return r.render();
  };
  // The filtered lookups (with their footprints) of a constant map are that constant too.
  for (auto filter : {TextureFilter::kBilinear, TextureFilter::kMipmap})
    for (auto model : {IceModel::kMonograph, IceModel::kPhysical})
      for (bool dispersion : {false, true})
        for (auto mode : {FresnelMode::kFull, FresnelMode::kSchlick}) {
          const RgbImage img = run(model, dispersion, mode, filter);
          double worst = 0;
          for (float v : img.values()) worst = std::max(worst, std::abs(static_cast<double>(v) - L));
          // Monograph: F·L + (1 - F)·L, float storage only. Physical: paths dropped once their
          // weight is below 1e-4 (measured: ≤ 7e-5 of L).
          const double tol = model == IceModel::kMonograph ? 1e-6 : 2e-4;
          EXPECT_LT(worst, tol * L) << (model == IceModel::kPhysical ? "physical" : "monograph") << " dispersion "
                                    << dispersion << " schlick " << (mode == FresnelMode::kSchlick) << " mipmap "
                                    << (filter == TextureFilter::kMipmap);
        }
}

TEST(MeshBvh, RefitsWhenOnlyPositionsMoveAndRebuildsOtherwise) {
  MeshBvh bvh;
  auto m = sim::TriMesh<double>::from_indexed(sphere(1.0, Vector3d::Zero()));
  EXPECT_EQ(bvh.update(m), BvhUpdate::kRebuild);
  MeshHit h;
  ASSERT_TRUE(bvh.intersect(Vector3d(0, 0, 5), Vector3d(0, 0, -1), 0, 100, h));
  EXPECT_NEAR(h.t, 4.0, 1e-2);
  EXPECT_GT(h.ng.z(), 0.99);
  for (std::size_t v = 0; v < m.vertex_slots(); ++v) m.position.set(v, m.position[v] * 0.5);  // shrink: same triangles
  EXPECT_EQ(bvh.update(m), BvhUpdate::kRefit);
  ASSERT_TRUE(bvh.intersect(Vector3d(0, 0, 5), Vector3d(0, 0, -1), 0, 100, h));
  EXPECT_NEAR(h.t, 4.5, 1e-2);
  m.triangle_alive[0] = 0;  // a triangle melted away
  EXPECT_EQ(bvh.update(m), BvhUpdate::kRebuild);
  EXPECT_EQ(bvh.triangle_count(), m.live_triangle_count());
  sim::TriMesh<double> empty;
  EXPECT_EQ(bvh.update(empty), BvhUpdate::kNone);
  EXPECT_FALSE(bvh.intersect(Vector3d(0, 0, 5), Vector3d(0, 0, -1), 0, 100, h));
}

TEST(RenderScene, ParsesAndRefusesUnknownKeys) {
  const auto s = parse_render_scene(
      YAML::Load("{width: 64, height: 48, texture_filter: mipmap, ice: {model: physical, fresnel: schlick, ct: 0},"
                 " ground: {a: 0.5}, outputs: {exr: false}}"),
      "scene.yaml");
  EXPECT_EQ(s.width, 64);
  EXPECT_EQ(s.texture_filter, TextureFilter::kMipmap);
  EXPECT_EQ(parse_render_scene(YAML::Load("{}"), "scene.yaml").texture_filter, TextureFilter::kBilinear);
  EXPECT_EQ(s.ice.model, IceModel::kPhysical);
  EXPECT_EQ(s.ice.fresnel, FresnelMode::kSchlick);
  EXPECT_EQ(s.ice.ct, 0.0);
  EXPECT_EQ(s.ground.a, 0.5);
  EXPECT_FALSE(s.outputs.exr);
  auto message = [](const std::string& y) {
    try {
      parse_render_scene(YAML::Load(y), "scene.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(message("{ice: {cx: 1}}").find("scene.yaml:1: ice: unknown key 'cx'"), std::string::npos)
      << message("{ice: {cx: 1}}");
  EXPECT_NE(message("{ice: {fresnel: exact}}").find("'ice.fresnel' must be one of"), std::string::npos);
  EXPECT_NE(message("{texture_filter: trilinear}").find("'texture_filter' must be one of"), std::string::npos);
  EXPECT_NE(message("{environment: {layout: sphere}}").find("'environment.layout' must be one of"), std::string::npos);
  EXPECT_NE(message("{ground: {a: -1}}").find("'ground.a' must be in"), std::string::npos);
  EXPECT_EQ(message("width: 64\nice:\n  eta: 1.3\n  ct: 0\n  eta: 1.4\n"),
            "scene.yaml:5: ice: key 'eta' appears twice");
  EXPECT_EQ(message("outputs:\n  exr: false\n  png: no\n"),
            "scene.yaml:2: outputs: at least one of 'exr' and 'png' must be true");
  EXPECT_NE(message("{lights: [{to_light: [0, 0, 0]}]}").find("zero vector"), std::string::npos);
}

// Image files named in the scene YAML (relative to the scene file) replace the procedural
// assets; the dry ground is then Phong times the file's texture, bilinearly wrapped.
TEST(RenderScene, ImageFilesReplaceTheProceduralAssets) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("meltlab_scene_files_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "tex");
  RgbImage tex = rgb_image(4, 4), env = rgb_image(8, 4);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) set_rgb(tex, i, j, Rgb(0.1 + 0.2 * i, 0.1 + 0.2 * j, 0.5));
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 8; ++i) set_rgb(env, i, j, Rgb(0.25, 0.5, 1.0));
  write_exr(dir / "tex" / "ground.exr", tex);
  write_exr(dir / "sky.exr", env);
  const std::string scene_file = (dir / "scene.yaml").string();
  const RenderScene parsed =
      parse_render_scene(YAML::Load("{ground: {texture: tex/ground.exr}, environment: {file: sky.exr}}"), scene_file);
  EXPECT_EQ(parsed.ground.texture_file, dir / "tex" / "ground.exr");
  EXPECT_EQ(parsed.environment.file, dir / "sky.exr");
  // The EXR round trip (half float: 11 significant bits).
  const RgbImage back = read_rgb_image(parsed.ground.texture_file);
  ASSERT_EQ(back.width(), 4);
  EXPECT_NEAR((rgb_at(back, 3, 2) - rgb_at(tex, 3, 2)).norm(), 0.0, 1e-3);

  auto s = dry_ground_scene(32, 32, 10.0);
  s.ground.texture_file = parsed.ground.texture_file;
  s.environment.file = parsed.environment.file;
  IceRenderer r(s);
  r.set_mesh(sphere(0.1, Vector3d(100, 100, 1)));  // far outside the view
  const RgbImage img = r.render();
  for (int j = 0; j < 32; j += 5)
    for (int i = 0; i < 32; i += 7) {
      const double x = (i - 15.5) / 10.0, y = -(j - 15.5) / 10.0;
      const Rgb want =
          0.7 * sample_bilinear_rgb(back, x / 2.0 * 4 - 0.5, y / 2.0 * 4 - 0.5, ImageWrap::kRepeat, ImageWrap::kRepeat);
      EXPECT_NEAR((pixel(img, i, j) - want).norm(), 0.0, kPixelTol) << i << "," << j;
    }

  auto message = [&](const std::string& y) {
    try {
      parse_render_scene(YAML::Load(y), scene_file);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(message("{environment: {file: nope.exr}}").find("no such image file"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// ---- reference images ----------------------------------------------------------------
// 64x48 frames of a small scene, stored as PNGs in tests/assets/render_ice/. Set
// MELTLAB_UPDATE_REFERENCES=1 to rewrite them (then look at them before committing).

RgbImage reference_frame(IceModel model, bool normal_map) {
  RenderScene s;
  s.width = 64;
  s.height = 48;
  s.ice.model = model;
  s.ice.normal_map = normal_map;
  s.ground.z = 0.0;
  IceRenderer r(s);
  auto m = datasets::icosphere(3, 1.0);
  for (auto& v : m.V) v = Vector3d(v.x() * 1.2, v.y(), v.z() * 0.8 + 0.8);  // an ellipsoid lump on the ground
  r.set_mesh(m);
  sim::LiquidMaskParams mp = sim::LiquidMaskParams::around(m, 64, 3.0);
  mp.threshold = 0.3f;
  sim::LiquidMask mask(mp);
  const auto tri = sim::TriMesh<double>::from_indexed(m);
  for (int c = 0; c < 40; ++c) mask.step(tri, false);
  r.set_liquid(&mask);
  return r.render();
}

void compare_with_reference(const RgbImage& img, const std::string& name) {
  const char* dir = std::getenv("MELTLAB_TEST_DATA");
  ASSERT_NE(dir, nullptr) << "MELTLAB_TEST_DATA is not set";
  const std::filesystem::path file = std::filesystem::path(dir) / "render_ice" / (name + ".png");
  if (std::getenv("MELTLAB_UPDATE_REFERENCES")) {
    std::filesystem::create_directories(file.parent_path());
    write_png(file, img);
    GTEST_SKIP() << "wrote " << file;
  }
  // Compare in the display encoding the file was written in.
  const std::filesystem::path tmp = std::filesystem::temp_directory_path() / ("meltlab_" + name + "_now.png");
  write_png(tmp, img);
  const RgbImage now = read_png(tmp), ref = read_png(file);
  std::filesystem::remove(tmp);
  ASSERT_EQ(now.width(), ref.width());
  ASSERT_EQ(now.height(), ref.height());
  double sum = 0;
  int bad = 0;
  for (std::size_t k = 0; k < now.values().size(); ++k) {
    const double e = std::abs(static_cast<double>(now.values()[k] - ref.values()[k]));
    sum += e;
    bad += e > 8.0 / 255.0;
  }
  EXPECT_LE(sum / static_cast<double>(now.values().size()), kRefMeanTol) << name;
  EXPECT_LE(bad, static_cast<int>(kRefBadPixelFraction * static_cast<double>(now.values().size()))) << name;
}

TEST(ReferenceImages, MonographMaterialOnWetGround) {
  compare_with_reference(reference_frame(IceModel::kMonograph, false), "monograph");
}
TEST(ReferenceImages, NormalMappedIce) {
  compare_with_reference(reference_frame(IceModel::kMonograph, true), "normal_mapped");
}
TEST(ReferenceImages, PhysicalReference) {
  compare_with_reference(reference_frame(IceModel::kPhysical, false), "physical");
}

}  // namespace
}  // namespace meltlab::render
