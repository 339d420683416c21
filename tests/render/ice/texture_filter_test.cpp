// Filtered texture lookups (texture/filtered.h) and the one lookup interface over them and
// the bilinear ones (texture/lookup.h), cube-map environments (texture/assets.h),
// the ray differentials that give the footprints (material/optics.h, MeshBvh), and the point of it all:
// MIP-mapping brings a 1-sample-per-pixel frame closer to a supersampled one.

#include <meltlab/datasets/procedural.h>
#include <meltlab/render/embree/mesh_bvh.h>
#include <meltlab/render/texture/filtered.h>
#include <meltlab/render/texture/lookup.h>
#include <meltlab/render/integrator/ice_surface.h>
#include <meltlab/render/material/optics.h>
#include <meltlab/render/texture/assets.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <numbers>
#include <random>

namespace meltlab::render {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

// A zero-footprint lookup is OpenImageIO's bilinear interpolation in float of float texels:
// a few float roundings of values in [0, 1].
constexpr double kFloatLookupTol = 1e-5;
// Ray differentials against central finite differences with step h = 1e-6: the truncation
// error is O(h²)·|third derivative| and the rounding error O(1e-16/h) ≈ 1e-10.
constexpr double kDifferentialTol = 1e-7;

RgbImage random_image(int w, int h, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  RgbImage img = rgb_image(w, h);
  for (auto& v : img.values()) v = u(rng);
  return img;
}

TEST(FilteredTextures, ZeroFootprintIsTheBilinearLookup) {
  const RgbImage tex = random_image(64, 32, 1), env = random_image(64, 32, 2);
  FilteredTextures ft;
  const int t_id = ft.add(tex, FilteredTextures::Kind::kTexture, "tex");
  const int e_id = ft.add(env, FilteredTextures::Kind::kLatLongEnvironment, "env");
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.5, 2.5), g(-1.0, 1.0);
  for (int k = 0; k < 500; ++k) {
    const double s = u(rng), t = u(rng);  // outside [0, 1) too: periodic
    const Vector3d want =
        sample_bilinear_rgb(tex, s * tex.width() - 0.5, t * tex.height() - 0.5, ImageWrap::kRepeat, ImageWrap::kRepeat);
    EXPECT_NEAR((ft.texture(t_id, s, t, Vector2d::Zero(), Vector2d::Zero()) - want).norm(), 0.0, kFloatLookupTol)
        << s << " " << t;
    Vector3d dir(g(rng), g(rng), g(rng));
    if (std::abs(dir.normalized().z()) > 0.95) continue;  // OpenImageIO blends towards the pole's average near it
    const Vector3d got = ft.environment(e_id, dir, Vector3d::Zero(), Vector3d::Zero());
    EXPECT_NEAR((got - sample_latlong(env, dir)).norm(), 0.0, kFloatLookupTol) << dir.transpose();
  }
}

TEST(FilteredTextures, WideFootprintAveragesAFineCheckerboard) {
  RgbImage checker = rgb_image(64, 64);
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 64; ++i) set_rgb(checker, i, j, Vector3d::Constant((i + j) % 2));
  FilteredTextures ft;
  const int id = ft.add(checker, FilteredTextures::Kind::kTexture, "checker");
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 100; ++k) {
    const double s = u(rng), t = u(rng);
    // Isotropic (8 texels) and anisotropic (16 x 2 texels, rotated) footprints.
    const Vector3d iso = ft.texture(id, s, t, Vector2d(8.0 / 64, 0), Vector2d(0, 8.0 / 64));
    const Vector3d aniso = ft.texture(id, s, t, Vector2d(11.3 / 64, 11.3 / 64), Vector2d(-1.4 / 64, 1.4 / 64));
    EXPECT_NEAR(iso.x(), 0.5, 0.02);
    EXPECT_NEAR(aniso.x(), 0.5, 0.05);
    // ...while a point lookup at a texel centre sees the texel.
    const int i = static_cast<int>(s * 64), j = static_cast<int>(t * 64);
    EXPECT_NEAR(ft.texture(id, (i + 0.5) / 64, (j + 0.5) / 64, Vector2d::Zero(), Vector2d::Zero()).x(), (i + j) % 2,
                kFloatLookupTol);
  }
}

TEST(TextureLookup, BilinearIsTheCoreLookupWhateverTheFootprint) {
  const RgbImage tex = random_image(64, 32, 6), env = random_image(64, 32, 7);
  TextureFactory factory(TextureFilter::kBilinear);
  ASSERT_FALSE(factory.uses_footprints());
  const auto image = factory.image(tex, "tex");
  const auto environment = factory.environment(env, "env");
  const Differential2 wide{Vector2d(0.3, 0.1), Vector2d(-0.2, 0.4)};
  const Differential wide_dir{Vector3d(0.1, 0.2, 0.0), Vector3d(0.0, -0.3, 0.1)};
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-1.5, 2.5), g(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Vector2d st(u(rng), u(rng));
    const Vector3d want = sample_bilinear_rgb(tex, st.x() * tex.width() - 0.5, st.y() * tex.height() - 0.5,
                                              ImageWrap::kRepeat, ImageWrap::kRepeat);
    EXPECT_EQ(image->lookup(st, nullptr), want);
    EXPECT_EQ(image->lookup(st, &wide), want);
    const Vector3d dir(g(rng), g(rng), g(rng));
    EXPECT_EQ(environment->lookup(dir, nullptr), sample_latlong(env, dir));
    EXPECT_EQ(environment->lookup(dir, &wide_dir), sample_latlong(env, dir));
  }
}

TEST(TextureLookup, BothFiltersAgreeWithoutAFootprint) {
  const RgbImage tex = random_image(32, 32, 9), env = random_image(64, 32, 10);
  TextureFactory bilinear(TextureFilter::kBilinear), mipmap(TextureFilter::kMipmap);
  ASSERT_TRUE(mipmap.uses_footprints());
  const auto b_image = bilinear.image(tex, "tex"), m_image = mipmap.image(tex, "tex");
  const auto b_env = bilinear.environment(env, "env"), m_env = mipmap.environment(env, "env");
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.5, 2.5), g(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const Vector2d st(u(rng), u(rng));
    EXPECT_NEAR((m_image->lookup(st, nullptr) - b_image->lookup(st, nullptr)).norm(), 0.0, kFloatLookupTol);
    const Vector3d dir(g(rng), g(rng), g(rng));
    if (std::abs(dir.normalized().z()) > 0.95) continue;  // OpenImageIO blends towards the pole's average near it
    EXPECT_NEAR((m_env->lookup(dir, nullptr) - b_env->lookup(dir, nullptr)).norm(), 0.0, kFloatLookupTol);
  }
  // A wide footprint on the MIP-mapped texture reads a coarser level: a different value.
  const Differential2 wide{Vector2d(0.5, 0.0), Vector2d(0.0, 0.5)};
  const Vector2d st(0.3, 0.6);
  EXPECT_GT((m_image->lookup(st, &wide) - b_image->lookup(st, nullptr)).norm(), 0.01);
}

TEST(TextureLookup, ProjectionReadsThePlaneAcrossTheAxis) {
  const auto image = TextureFactory(TextureFilter::kBilinear).image(random_image(16, 16, 12), "tex");
  const Vector3d x(0.3, -0.7, 1.9);
  const double tile = 0.5;
  EXPECT_EQ(lookup_projected(*image, x, 0, tile, nullptr), image->lookup(Vector2d(x.y(), x.z()) / tile, nullptr));
  EXPECT_EQ(lookup_projected(*image, x, 1, tile, nullptr), image->lookup(Vector2d(x.x(), x.z()) / tile, nullptr));
  EXPECT_EQ(lookup_projected(*image, x, 2, tile, nullptr), image->lookup(Vector2d(x.x(), x.y()) / tile, nullptr));
  EXPECT_EQ(dominant_axis(Vector3d(0.9, -0.1, 0.3)), 0);
  EXPECT_EQ(dominant_axis(Vector3d(0.2, -0.9, 0.3)), 1);
  EXPECT_EQ(dominant_axis(Vector3d(0.2, 0.1, -0.5)), 2);
}

TEST(RayDifferentials, ReflectAndRefractMatchFiniteDifferences) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> g(-1.0, 1.0);
  constexpr double h = 1e-6;
  int refracted = 0;
  for (int k = 0; k < 200; ++k) {
    const Vector3d n = Vector3d(g(rng), g(rng), g(rng)).normalized();
    Vector3d v = Vector3d(g(rng), g(rng), g(rng)).normalized();
    if (v.dot(n) < 0.05) v = (v - 2 * v.dot(n) * n + 0.1 * n).normalized();  // on the normal's side
    const Vector3d dv = Vector3d(g(rng), g(rng), g(rng)), dn = Vector3d(g(rng), g(rng), g(rng));
    auto unit_reflect = [&](double e) { return reflect(v + e * dv, (n + e * dn).normalized()); };
    // The derivative of the normalised normal, as the renderer passes it.
    const Vector3d dn_unit = dn - n * n.dot(dn);
    const Vector3d fd_r = (unit_reflect(h) - unit_reflect(-h)) / (2 * h);
    EXPECT_NEAR((reflect_differential(v, dv, n, dn_unit) - fd_r).norm(), 0.0, kDifferentialTol * (1 + fd_r.norm()));
    for (double eta : {1.0 / 1.31, 1.31}) {
      const Vector3d i0 = -v;
      auto unit_refract = [&](double e) { return refract((i0 - e * dv).normalized(), (n + e * dn).normalized(), eta); };
      const auto plus = unit_refract(h), minus = unit_refract(-h);
      if (!plus || !minus) continue;  // at or near total internal reflection
      ++refracted;
      const Vector3d di = -(dv - i0 * i0.dot(dv));  // the derivative of the normalised incident ray
      const Vector3d fd_t = (*plus - *minus) / (2 * h);
      EXPECT_NEAR((refract_differential(i0, di, n, dn_unit, eta) - fd_t).norm(), 0.0, 1e-6 * (1 + fd_t.norm())) << eta;
    }
  }
  EXPECT_GT(refracted, 250);
}

TEST(RayDifferentials, ShadingNormalDifferentialMatchesFiniteDifferences) {
  auto m = datasets::icosphere(2, 1.0);
  MeshBvh bvh;
  bvh.update(m);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> g(-1.0, 1.0);
  int tested = 0;
  for (int k = 0; k < 100; ++k) {
    const Vector3d dir = Vector3d(g(rng), g(rng), g(rng)).normalized();
    MeshHit hit;
    ASSERT_TRUE(bvh.intersect(Vector3d::Zero(), dir, 0.0, 10.0, hit));
    // A step within the triangle's plane.
    Vector3d dp = Vector3d(g(rng), g(rng), g(rng));
    dp -= hit.ng * hit.ng.dot(dp);
    dp *= 1e-3;
    // Move the barycentrics by the step: p + dp has (u + du, v + dv); shading_normal there.
    const Vector3d dn = bvh.shading_normal_differential(hit, dp);
    const Vector3d p = dir * hit.t;
    MeshHit moved;
    if (!bvh.intersect(Vector3d::Zero(), (p + dp).normalized(), 0.0, 10.0, moved) || moved.prim != hit.prim) continue;
    // The moved ray meets the same plane at p + dp' with dp' ≈ dp (to first order it is exactly p + dp's projection).
    const Vector3d p_moved = (p + dp).normalized() * moved.t;
    const Vector3d want = bvh.shading_normal(moved) - bvh.shading_normal(hit);
    const Vector3d got = bvh.shading_normal_differential(hit, p_moved - p);
    EXPECT_NEAR((got - want).norm(), 0.0, 0.02 * want.norm() + 1e-9);
    EXPECT_GT(dn.norm(), 0.0);
    ++tested;
  }
  EXPECT_GT(tested, 50);
}

// ---- cube maps --------------------------------------------------------------------------

// A smooth environment to store in the faces: distinct in every component of the direction.
Vector3d analytic_sky(const Vector3d& d) { return Vector3d(0.5 + 0.4 * d.x(), 0.5 + 0.4 * d.y(), 0.5 + 0.4 * d.z()); }

// The world direction through the centre of texel (x, y) of face f (px nx py ny pz nz) in the
// cube frame of texture/assets.h, written out from the face table (major axis, +column, +row).
Vector3d face_texel_direction(int f, double s, double t) {
  const double a = 2 * s - 1, b = 2 * t - 1;  // along +column and +row
  const Vector3d X = Vector3d::UnitX(), Y = Vector3d::UnitY(), Z = Vector3d::UnitZ();
  const Vector3d major[6] = {X, -X, Y, -Y, Z, -Z};
  const Vector3d col[6] = {-Z, Z, X, X, X, -X};
  const Vector3d row[6] = {-Y, -Y, Z, -Z, -Y, -Y};
  const Vector3d c = (major[f] + a * col[f] + b * row[f]).normalized();
  return Vector3d(c.z(), -c.x(), c.y());  // cube (cx, cy, cz) = world (-y, z, x)
}

struct Layout {
  EnvironmentLayout layout;
  int cols, rows;
  int cell[6][3];  // col, row, rotated
};
const Layout kLayouts[] = {
    {EnvironmentLayout::kCube3x2, 3, 2, {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}, {2, 0, 0}, {2, 1, 0}}},
    {EnvironmentLayout::kCube1x6, 1, 6, {{0, 0, 0}, {0, 1, 0}, {0, 2, 0}, {0, 3, 0}, {0, 4, 0}, {0, 5, 0}}},
    {EnvironmentLayout::kCrossHorizontal, 4, 3, {{2, 1, 0}, {0, 1, 0}, {1, 0, 0}, {1, 2, 0}, {1, 1, 0}, {3, 1, 0}}},
    {EnvironmentLayout::kCrossVertical, 3, 4, {{2, 1, 0}, {0, 1, 0}, {1, 0, 0}, {1, 2, 0}, {1, 1, 0}, {1, 3, 1}}},
};

RgbImage cube_image(const Layout& l, int F, const std::function<Vector3d(int, const Vector3d&)>& value) {
  RgbImage img = rgb_image(l.cols * F, l.rows * F);
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < F; ++y)
      for (int x = 0; x < F; ++x) {
        const Vector3d d = face_texel_direction(f, (x + 0.5) / F, (y + 0.5) / F);
        const int sx = l.cell[f][2] ? F - 1 - x : x, sy = l.cell[f][2] ? F - 1 - y : y;
        set_rgb(img, l.cell[f][0] * F + sx, l.cell[f][1] * F + sy, value(f, d));
      }
  return img;
}

// A private temporary folder for the image files a test writes.
class TextureFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("meltlab_texture_files_" + std::to_string(::getpid()) + "_" +
                                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};
class CubeMaps : public TextureFiles {};
class IceTexture : public TextureFiles {};
class FilteredFrames : public TextureFiles {};

TEST_F(CubeMaps, EveryLayoutGivesTheSameEnvironment) {
  constexpr int F = 48;
  // Bilinear within a face of F texels over 90°: the analytic sky's slope is 0.4 per radian and
  // a texel spans at most π/(2F) rad; plus the half-float storage of the EXR (1e-3 at 1).
  const double tol = 0.4 * std::numbers::pi / (2 * F) + 1e-3;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> g(-1.0, 1.0);
  for (const Layout& l : kLayouts) {
    const auto file = dir_ / fmt::format("{}.exr", environment_layout_name(l.layout));
    write_exr(file, cube_image(l, F, [](int, const Vector3d& d) { return analytic_sky(d); }));
    for (auto how : {EnvironmentLayout::kAuto, l.layout}) {
      const RgbImage env = read_environment(file, how);
      EXPECT_EQ(env.width(), 4 * F);
      EXPECT_EQ(env.height(), 2 * F);
      double worst = 0;
      for (int k = 0; k < 1000; ++k) {
        const Vector3d d = Vector3d(g(rng), g(rng), g(rng)).normalized();
        worst = std::max(worst, (sample_latlong(env, d) - analytic_sky(d)).cwiseAbs().maxCoeff());
      }
      EXPECT_LT(worst, tol) << environment_layout_name(l.layout);
    }
  }
}

TEST_F(CubeMaps, FacesLandWhereTheFrameSays) {
  // Solid faces: the sky (world +z) is py, world +x is pz, world +y is nx (cube = (-y, z, x)).
  const Vector3d colour[6] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {0, 1, 1}, {1, 0, 1}};
  const auto file = dir_ / "faces.png";
  write_png(file, cube_image(kLayouts[2], 16, [&](int f, const Vector3d&) { return colour[f]; }));
  const RgbImage env = read_environment(file);
  EXPECT_NEAR((sample_latlong(env, Vector3d::UnitZ()) - colour[2]).norm(), 0.0, 1e-6);   // py
  EXPECT_NEAR((sample_latlong(env, -Vector3d::UnitZ()) - colour[3]).norm(), 0.0, 1e-6);  // ny
  EXPECT_NEAR((sample_latlong(env, Vector3d::UnitX()) - colour[4]).norm(), 0.0, 1e-6);   // pz
  EXPECT_NEAR((sample_latlong(env, -Vector3d::UnitX()) - colour[5]).norm(), 0.0, 1e-6);  // nz
  EXPECT_NEAR((sample_latlong(env, Vector3d::UnitY()) - colour[1]).norm(), 0.0, 1e-6);   // nx
  EXPECT_NEAR((sample_latlong(env, -Vector3d::UnitY()) - colour[0]).norm(), 0.0, 1e-6);  // px
}

TEST_F(CubeMaps, SizesThatFitNoLayoutAreRefused) {
  auto message = [&](int w, int h, EnvironmentLayout how) {
    const auto file = dir_ / fmt::format("odd_{}x{}.png", w, h);
    write_png(file, rgb_image(w, h));
    try {
      read_environment(file, how);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(message(50, 30, EnvironmentLayout::kAuto).find("neither a 2:1 lat-long map nor a cube map"),
            std::string::npos);
  EXPECT_NE(message(50, 30, EnvironmentLayout::kAuto).find("odd_50x30.png"), std::string::npos);
  EXPECT_NE(message(30, 21, EnvironmentLayout::kCube3x2).find("3 x 2 square faces"), std::string::npos);
  EXPECT_EQ(message(30, 20, EnvironmentLayout::kCube3x2), "(no error)");
  EXPECT_EQ(message(30, 21, EnvironmentLayout::kLatLong), "(no error)");  // any size is a lat-long map
}

// ---- frames ----------------------------------------------------------------------------

// The ice texture from an image: ambient only (ca = 1, every other term 0), so an ice pixel
// is tdiff itself. A ramp in u (red = u) projected along z with period 4 on the top of a
// sphere centred at (2, 2): red = x / 4 where the normal is mostly vertical.
TEST_F(IceTexture, FileIsProjectedAlongTheDominantAxis) {
  RgbImage ramp = rgb_image(64, 64);
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 64; ++i) set_rgb(ramp, i, j, Vector3d((i + 0.5) / 64, 0.0, 0.5));
  const auto file = dir_ / "ramp.exr";
  write_exr(file, ramp);
  for (auto filter : {TextureFilter::kBilinear, TextureFilter::kMipmap}) {
    RenderScene s;
    s.texture_filter = filter;
    OrthographicTopDown cam;
    cam.width = cam.height = 64;
    cam.pixels_per_unit = 20;
    cam.centre = Eigen::Vector2d(2, 2);
    s.camera = cam;
    s.ice.ca = 1.0;
    s.ice.cd = s.ice.cs = s.ice.cr = s.ice.ct = 0.0;
    s.ice.texture_file = file;
    s.ice.texture_tile = 4.0;
    s.ground.z = -1.0;
    IceRenderer r(s);
    auto m = datasets::icosphere(4, 1.0);
    for (auto& v : m.V) v += Vector3d(2, 2, 0);
    r.set_mesh(m);
    const RgbImage img = r.render();
    int checked = 0;
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        const double x = 2 + (i - 31.5) / 20, y = 2 - (j - 31.5) / 20;
        if (std::hypot(x - 2, y - 2) > 0.5) continue;  // the top cap: z is the dominant axis
        const Vector3d c = rgb_at(img, i, j);
        // Half-float texels (1e-3) and, for mipmap, a footprint of 1/20 unit = 0.8 texel.
        EXPECT_NEAR(c.x(), x / 4, 2e-3) << i << "," << j;
        EXPECT_NEAR(c.z(), 0.5, 1e-3);
        ++checked;
      }
    EXPECT_GT(checked, 250);
  }
}

// The ground seen at a grazing angle: a checkerboard (16 squares per 2-unit period) that is
// resolved near the camera recedes to the horizon, where many squares fall into a pixel. Rendered at 1 sample per pixel
// with bilinear and with MIP-mapped lookups, and at 8x8 samples per pixel (an 8x larger frame, box-filtered down) as
// the reference.
RgbImage grazing_ground(TextureFilter filter, int scale, const std::filesystem::path& texture) {
  RenderScene s;
  s.texture_filter = filter;
  s.lights = {DirectionalLight{Vector3d(0, 0, 1), Rgb(1, 1, 1)}};
  s.ground.z = 0.0;
  s.ground.tile = 2.0;
  s.ground.ca = 0.3;
  s.ground.cd = 0.7;
  s.ground.cs = 0.0;
  s.ground.texture_file = texture;
  s.environment.constant = 0.5;
  const int w = 96 * scale, h = 64 * scale;
  s.camera = Pinhole::look_at(w, h, 80.0 * scale, Vector3d(0, -4, 0.6), Vector3d(0, 4, 0), Vector3d(0, 0, 1));
  IceRenderer r(s);
  r.set_mesh(datasets::icosphere(1, 0.01));  // a speck far below the view: the BVH needs a mesh
  return r.render();
}

RgbImage box_down(const RgbImage& big, int k) {
  RgbImage out = rgb_image(big.width() / k, big.height() / k);
  for (int j = 0; j < out.height(); ++j)
    for (int i = 0; i < out.width(); ++i) {
      Vector3d sum = Vector3d::Zero();
      for (int y = 0; y < k; ++y)
        for (int x = 0; x < k; ++x) sum += rgb_at(big, k * i + x, k * j + y);
      set_rgb(out, i, j, sum / (k * k));
    }
  return out;
}

double rmse(const RgbImage& a, const RgbImage& b) {
  double s = 0;
  for (std::size_t k = 0; k < a.values().size(); ++k)
    s += std::pow(static_cast<double>(a.values()[k] - b.values()[k]), 2);
  return std::sqrt(s / static_cast<double>(a.values().size()));
}

TEST_F(FilteredFrames, MipMappingBringsOneSampleCloserToSupersampling) {
  RgbImage stripes = rgb_image(128, 128);
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 128; ++i) set_rgb(stripes, i, j, Vector3d::Constant(((i / 8) + (j / 8)) % 2 ? 0.9 : 0.1));
  const auto tex = dir_ / "stripes.exr";
  write_exr(tex, stripes);
  const RgbImage reference = box_down(grazing_ground(TextureFilter::kBilinear, 8, tex), 8);
  const RgbImage bilinear = grazing_ground(TextureFilter::kBilinear, 1, tex);
  const RgbImage mipmap = grazing_ground(TextureFilter::kMipmap, 1, tex);
  const double e_bilinear = rmse(bilinear, reference), e_mipmap = rmse(mipmap, reference);
  if (const char* out = std::getenv("MELTLAB_DUMP_FRAMES")) {  // to look at them
    write_png(std::filesystem::path(out) / "grazing_reference.png", reference);
    write_png(std::filesystem::path(out) / "grazing_bilinear.png", bilinear);
    write_png(std::filesystem::path(out) / "grazing_mipmap.png", mipmap);
  }
  std::printf("grazing ground, RMSE against 8x8 supersampling: bilinear %.4f, mipmap %.4f\n", e_bilinear, e_mipmap);
  // Measured: 0.0 bilinear, 0.0 mipmap (see the closing note); the filtered frame must be
  // clearly closer to the supersampled one.
  EXPECT_LT(e_mipmap, 0.6 * e_bilinear) << "bilinear " << e_bilinear << " mipmap " << e_mipmap;
}

}  // namespace
}  // namespace meltlab::render
