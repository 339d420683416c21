// The materials of the ice ray tracer, called directly through their interface (material/ice.h,
// material/ground.h) with hand-made hits and a fake of the integrator: closed forms of Eq. 6.11
// at normal incidence and at a lit point, the physical ice through a slab (Fresnel and Beer),
// Eq. 7.17 inside a puddle, and the liquid's wet-window shortcut against the full test.

#include <meltlab/render/material/ground.h>
#include <meltlab/render/material/ice.h>
#include <meltlab/render/material/optics.h>
#include <meltlab/render/texture/lookup.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace meltlab::render {
namespace {

using Eigen::Vector3d;

// Closed forms evaluated in double against the materials' double arithmetic (a few roundings,
// and the bilinear lookup of a uniform float map, exact to float storage of the value).
constexpr double kClosedFormTol = 1e-12;
// The physical ice drops an internally reflected path once its weight is below 1e-4
// (material/ice.cpp kMinPathWeight); with outside radiance at most 3 the truncation is below
// 3e-4 / (1 - F) of the infinite series.
constexpr double kPathCutTol = 4e-4;

std::unique_ptr<const EnvironmentTexture> uniform_environment(double radiance) {
  EnvironmentOptions o;
  o.width = 16;
  o.height = 8;
  o.constant = radiance;
  return TextureFactory(TextureFilter::kBilinear).environment(latlong_environment(o), "uniform");
}

std::unique_ptr<const ImageTexture> uniform_image(double value) {
  RgbImage img = rgb_image(4, 4);
  for (auto& v : img.values()) v = static_cast<float>(value);
  return TextureFactory(TextureFilter::kBilinear).image(img, "uniform");
}

// The top of a flat piece of ice at the origin seen straight from above.
SurfaceHit top_hit() { return SurfaceHit{Vector3d(0, 0, 1), Vector3d::UnitZ(), Vector3d::UnitZ(), {}}; }

double normal_fresnel(double eta) { return std::pow((eta - 1) / (eta + 1), 2); }

TEST(MonographIce, NormalIncidenceIsFresnelWeightedReflectionAndTransmission) {
  IceMaterial m;
  m.ca = m.cd = m.cs = 0;  // only the environment terms
  m.cr = 0.7;
  m.ct = 0.4;
  m.dispersion = false;
  std::vector<std::string> skipped;
  const IcePlan plan = plan_ice(m, true, skipped);
  ASSERT_FALSE(plan.ice_texture);
  ASSERT_FALSE(plan.ice_specular);
  const auto env = uniform_environment(2.0);
  const std::vector<Light> lights;
  const MonographIce ice(m, plan, IceTextures{env.get(), nullptr, nullptr}, lights);
  const Rgb I = ice.shade(top_hit(), -Vector3d::UnitZ(), nullptr);
  const double F = normal_fresnel(m.eta);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(I[c], 0.7 * F * 2.0 + 0.4 * (1 - F) * 2.0, kClosedFormTol) << c;
}

TEST(MonographIce, LitPointIsAmbientDiffuseTimesTextureAndSpecular) {
  IceMaterial m;
  m.ca = 0.1;
  m.cd = 0.3;
  m.cs = 0.6;
  m.n_spec = 2;
  m.cr = m.ct = 0;     // no environment terms
  m.texture_tile = 1;  // (the renderer resolves the size-relative 0)
  std::vector<std::string> skipped;
  const IcePlan plan = plan_ice(m, true, skipped);
  ASSERT_FALSE(plan.fresnel);
  const auto env = uniform_environment(5.0);
  const auto tex = uniform_image(0.5);
  // A red light 60° from the normal: N·L = ½; Rs·V = 2(N·L)(N·V) - L·V = ½.
  const std::vector<Light> lights{{Vector3d(std::sqrt(0.75), 0, 0.5), Rgb(1, 0, 0)}};
  const MonographIce ice(m, plan, IceTextures{env.get(), nullptr, tex.get()}, lights);
  const Rgb I = ice.shade(top_hit(), -Vector3d::UnitZ(), nullptr);
  const Rgb want(((0.1 + 0.3 * 0.5) * 0.5) + 0.6 * 0.25, 0.1 * 0.5, 0.1 * 0.5);
  EXPECT_NEAR((I - want).norm(), 0.0, kClosedFormTol) << I.transpose();
}

// The integrator as the physical ice sees it: a slab of ice between z = 0 and z = 1 (infinite
// in x and y), the scene outside sending `outside` along every ray.
class Slab final : public IceSurroundings {
 public:
  explicit Slab(const Rgb& outside) : outside_(outside) {}
  std::optional<SurfaceCrossing> next_crossing(const Vector3d& o, const Vector3d& d, double t_min) const override {
    if (d.z() == 0) return std::nullopt;
    const double z = d.z() > 0 ? 1.0 : 0.0;
    const double t = (z - o.z()) / d.z();
    if (!(t > t_min)) return std::nullopt;
    return SurfaceCrossing{t, Vector3d(0, 0, d.z() > 0 ? 1.0 : -1.0)};
  }
  Rgb radiance_outside(const Vector3d&, const Vector3d&, const RayDifferential*) const override {
    ++calls;
    return outside_;
  }
  mutable int calls = 0;

 private:
  Rgb outside_;
};

TEST(PhysicalIce, SlabAtNormalIncidenceIsFresnelAndBeer) {
  IceMaterial m;
  m.model = IceModel::kPhysical;
  m.dispersion = false;
  m.absorption = {0.5, 1.0, 2.0};
  std::vector<std::string> skipped;
  const IcePlan plan = plan_ice(m, true, skipped);
  const auto env = uniform_environment(0.0);
  const Rgb outside(1, 2, 3);
  const double eps = 1e-6, F = normal_fresnel(m.eta);
  {  // one pass: reflected F·L, transmitted (1 - F)² e^(-σ d) L with d = 1 - eps (the entry offset)
    m.max_internal_bounces = 0;
    const Slab slab(outside);
    const PhysicalIce ice(m, plan, IceTextures{env.get(), nullptr, nullptr}, slab, eps);
    const Rgb I = ice.shade(top_hit(), -Vector3d::UnitZ(), nullptr);
    EXPECT_EQ(slab.calls, 2);  // the mirrored ray and the one out of the bottom
    for (int c = 0; c < 3; ++c) {
      const double T = std::exp(-m.absorption[static_cast<std::size_t>(c)] * (1 - eps));
      EXPECT_NEAR(I[c], F * outside[c] + (1 - F) * (1 - F) * T * outside[c], kClosedFormTol) << c;
    }
  }
  {  // with the internal reflections: the series Σ_k F^k e^(-σ (k+1)) of the passes
    m.max_internal_bounces = 64;
    const Slab slab(outside);
    const PhysicalIce ice(m, plan, IceTextures{env.get(), nullptr, nullptr}, slab, eps);
    const Rgb I = ice.shade(top_hit(), -Vector3d::UnitZ(), nullptr);
    EXPECT_GT(slab.calls, 2);
    for (int c = 0; c < 3; ++c) {
      const double T = std::exp(-m.absorption[static_cast<std::size_t>(c)]);
      EXPECT_NEAR(I[c], F * outside[c] + (1 - F) * (1 - F) * T / (1 - F * T) * outside[c], kPathCutTol) << c;
    }
  }
}

sim::LiquidMask random_mask(std::uint32_t seed) {
  sim::LiquidMaskParams mp;
  mp.width = 24;
  mp.height = 20;
  mp.texel_size = 0.1;
  mp.origin = Eigen::Vector2d(-1.2, -1.0);
  mp.threshold = 0.5f;
  sim::LiquidMask mask(mp);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  // A puddle (values 1) in the middle, random values around it, dry texels at the edges.
  for (int j = 0; j < mp.height; ++j)
    for (int i = 0; i < mp.width; ++i) {
      const int ring = std::min({i, j, mp.width - 1 - i, mp.height - 1 - j});
      mask.values()[static_cast<std::size_t>(j) * mp.width + i] = ring < 3 ? 0.0f : (ring > 6 ? 1.0f : u(rng));
    }
  return mask;
}

TEST(LiquidFilm, WetWindowsChangeNoOutcome) {
  // The same mask with a constant threshold (the shortcut of per-texel windows is used) and with
  // a threshold texture of that constant (every test evaluated): the same w and N* everywhere,
  // in the puddle, on its rim, around it and beyond the grid.
  const sim::LiquidMask fast = random_mask(7);
  sim::LiquidMask full = random_mask(7);
  full.set_threshold_texture(std::vector<float>(full.values().size(), 0.5f));
  const LiquidFilm a(fast, 0.7, 0.7, true), b(full, 0.7, 0.7, true);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(-1.6, 1.6), y(-1.4, 1.4);
  int wet = 0, tilted = 0;
  for (int k = 0; k < 20000; ++k) {
    const Vector3d q(x(rng), y(rng), 0);
    const LiquidFilm::At fa = a.at(q), fb = b.at(q);
    ASSERT_EQ(fa.w, fb.w) << q.transpose();
    ASSERT_EQ(fa.n, fb.n) << q.transpose();
    wet += fa.w > 0;
    tilted += fa.n != Vector3d::UnitZ();
  }
  EXPECT_GT(wet, 1000);    // the comparison saw the puddle ...
  EXPECT_GT(tilted, 100);  // ... and its rim
}

TEST(WetGround, InsideThePuddleIsDarkenedPhongPlusTheWatersReflection) {
  GroundMaterial g;
  g.textured = false;
  g.ca = 0.2;
  g.cd = 0.5;
  g.cs = 0;
  g.a = 0.6;
  g.cr = 0.2;
  g.d = 0;
  g.tile = 1;
  sim::LiquidMaskParams mp;
  mp.width = mp.height = 10;
  mp.origin = Eigen::Vector2d(-5, -5);
  sim::LiquidMask mask(mp);
  std::fill(mask.values().begin(), mask.values().end(), 1.0f);
  std::vector<std::string> skipped;
  const GroundPlan plan = plan_ground(g, true, &mask, skipped);
  ASSERT_TRUE(plan.liquid);
  const auto env = uniform_environment(3.0);
  const auto tex = uniform_image(0.25);  // not looked up: the ground is not textured
  const std::vector<Light> lights{{Vector3d::UnitZ(), Rgb(1, 1, 1)}};
  const WetGround ground(g, plan, lights, *tex, *env, &mask);
  const Rgb I = ground.shade(Vector3d(0.3, -0.2, 0), Vector3d(0.2, 0.1, -1).normalized(), nullptr, nullptr);
  const double want = std::pow(0.2 + 0.5, 1.6) + 0.2 * 3.0;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(I[c], want, kClosedFormTol) << c;
  // Off the grid: plain Phong.
  const Rgb dry = ground.shade(Vector3d(40, 40, 0), -Vector3d::UnitZ(), nullptr, nullptr);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(dry[c], 0.7, kClosedFormTol) << c;
}

}  // namespace
}  // namespace meltlab::render
