// The volume integrator (render/integrator/volume_integrator.h) against the closed forms and
// identities of the seed-000 spec (../shared/spec/volume-lighting-raycast.md §5): slab
// intersection against a brute-force inside test (1), absorption / emission / emission–absorption
// slabs in continuous and discrete form with first-order convergence (2-4), HG normalisation and
// mean cosine (5), unshadowed and shadowed single scattering (6, 7), analytic against two-pass rays
// (14), compositing (15); and the integrator's own promises: serial == parallel, empty-space
// skipping and ERT, the shadow cache against the exact march.

#include <meltlab/core/error.h>
#include <meltlab/render/integrator/fast_exp.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/volume/generate.h>

#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace meltlab::render {
namespace {

using Vec3 = Eigen::Vector3d;

// The volume is sampled in float: a constant volume's trilinear value is exact to one float
// rounding per blend (~1e-7 relative), and the radiance is stored as float. Sums of up to a few
// hundred samples in double keep the relative error of closed-form comparisons below this.
constexpr double kFloatTolerance = 1e-6;

Volume constant_volume(const Box3& box, double value, int n = 8) {
  VolumeGenerateOptions g;
  g.kind = VolumeKind::kConstant;
  g.nx = g.ny = g.nz = n;
  g.constant = value;
  Volume v = generate_volume(g);
  v.fit_to_box(box);
  return v;
}

// A 1 x 1 pinhole whose only ray runs from `eye` through `target` (exactly along the axis for the
// axis-aligned set-ups below).
Camera one_ray(const Vec3& eye, const Vec3& target, const Vec3& up = Vec3::UnitZ()) {
  return Pinhole::look_at(1, 1, 1.0, eye, target, up);
}

// The box of sides (2, 3, 6): its diagonal is 7, so n = 7 · 2^m gives the dyadic step 2^-m and a ray
// along x through it (length 2) an integer number of steps.
Box3 box_2_3_6() { return Box3{Vec3(-1, -1.5, -3), Vec3(1, 1.5, 3)}; }

VolumeRenderSettings plain(OpticalModel model, int n) {
  VolumeRenderSettings s;
  s.model = model;
  s.samples = n;
  s.parallel = false;
  return s;
}

double centre_value(const VolumeFrame& f, int c = 0) { return f.radiance.at(0, 0, c); }
double centre_T(const VolumeFrame& f) { return f.transmittance.at(0, 0); }

TEST(VolumeIntegrator, FastExponentialIsAccurateOverItsDomain) {
  // Relative error against std::exp in double over [-86.9, 0] (a million points); 0 at and below -87.
  double worst = 0;
  for (int i = 0; i <= 1000000; ++i) {
    const float x = float(-86.9 * i / 1000000.0);
    const double exact = std::exp(double(x));
    worst = std::max(worst, std::abs(double(exp_nonpositive(x)) - exact) / exact);
  }
  EXPECT_LT(worst, 3e-7);  // 2.5 float ulp
  EXPECT_EQ(exp_nonpositive(0.0f), 1.0f);
  EXPECT_EQ(exp_nonpositive(-100.0f), 0.0f);
  EXPECT_EQ(exp_nonpositive(-std::numeric_limits<float>::infinity()), 0.0f);
}

// ---- target 1: slab intersection ----------------------------------------------------------------

bool inside(const Box3& b, const Vec3& p) { return b.contains(p); }

TEST(VolumeIntegrator, SlabIntersectionMatchesABruteForceInsideTest) {
  const Box3 box{Vec3(-1, -2, -0.5), Vec3(3, 1, 2)};
  const double d = box.diagonal();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  int hits = 0, misses = 0, checked = 0;
  for (int r = 0; r < 100000; ++r) {
    // An origin outside the box, on a sphere around it; a random direction, with some components
    // exactly 0.
    Vec3 o = box.centre() + 3 * d * Vec3(U(rng), U(rng), U(rng)).normalized();
    Vec3 v = Vec3(U(rng), U(rng), U(rng));
    if (r % 7 == 0) v.x() = 0;
    if (r % 11 == 0) v.y() = 0;
    if (r % 3 == 0) v = (box.centre() + Vec3(U(rng), U(rng), U(rng)).cwiseProduct(box.size()) * 0.6 - o);
    if (r % 13 == 0) {  // an axis-parallel ray through the box
      o = box.centre() + Vec3(U(rng), U(rng), 0).cwiseProduct(box.size()) * 0.4;
      o.z() = box.lo.z() - 1;
      v = Vec3::UnitZ();
    }
    if (v.norm() == 0) continue;
    v.normalize();
    const auto hit = intersect_box(box, o, v);
    // Brute force: a dense walk over the ray's reach for an inside point, then bisection on the
    // inside test for both ends.
    const double reach = 3 * d + 2 * d;
    const int kDense = 5000;
    double t_in = -1;
    for (int i = 0; i <= kDense; ++i) {
      const double t = reach * i / kDense;
      if (inside(box, o + t * v)) {
        t_in = t;
        break;
      }
    }
    if (t_in < 0) {
      // No dense sample inside: the analytic interval must miss or be shorter than the walk's step.
      if (hit) {
        EXPECT_LT(hit->t1 - hit->t0, 2 * reach / kDense) << r;
      }
      ++misses;
      continue;
    }
    ASSERT_TRUE(hit) << "ray " << r << " enters the box at t = " << t_in;
    auto bisect = [&](double a_in, double b_out) {
      for (int it = 0; it < 80; ++it) {
        const double m = 0.5 * (a_in + b_out);
        (inside(box, o + m * v) ? a_in : b_out) = m;
      }
      return 0.5 * (a_in + b_out);
    };
    const double t0 = t_in - reach / kDense <= 0 ? 0.0 : bisect(t_in, std::max(0.0, t_in - reach / kDense));
    double t_far = t_in;
    while (inside(box, o + (t_far + reach / kDense) * v)) t_far += reach / kDense;
    const double t1 = bisect(t_far, t_far + reach / kDense);
    EXPECT_NEAR(hit->t0, t0, 1e-5 * d) << r;
    EXPECT_NEAR(hit->t1, t1, 1e-5 * d) << r;
    ++hits;
    ++checked;
  }
  EXPECT_GT(hits, 30000);
  EXPECT_GT(misses, 10000);
  EXPECT_EQ(checked, hits);
}

TEST(VolumeIntegrator, SlabIntersectionRefusesBoxesBehindAndParallelMisses) {
  const Box3 box{Vec3(-1, -1, -1), Vec3(1, 1, 1)};
  EXPECT_FALSE(intersect_box(box, Vec3(0, 0, 5), Vec3(0, 0, 1)));   // behind
  EXPECT_FALSE(intersect_box(box, Vec3(0, 2, 5), Vec3(0, 0, -1)));  // parallel, outside the y slab
  EXPECT_FALSE(intersect_box(box, Vec3(5, 5, 0), Vec3(1, -1, 0).normalized()));
  const auto in = intersect_box(box, Vec3(0, 0, 0), Vec3(1, 0, 0));  // from inside
  ASSERT_TRUE(in);
  EXPECT_EQ(in->t0, -1.0);
  EXPECT_EQ(in->t1, 1.0);
}

// ---- targets 2-4: absorption, emission, emission–absorption slabs ------------------------------

TEST(VolumeIntegrator, AbsorptionSlabIsExactWhenThePathIsWholeSteps) {
  const double f0 = 0.5, kappa = 0.8, gamma = 2.0;
  const Volume v = constant_volume(box_2_3_6(), f0);
  VolumeRenderSettings s = plain(OpticalModel::kAbsorption, 7 * 16);  // Δs = 1/16, 32 steps over ℓ = 2
  s.kappa = kappa;
  s.gamma = gamma;
  const VolumeFrame f = render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s);
  const double I0 = 0.7;
  const double expected = I0 * std::exp(-kappa * std::pow(f0, gamma) * 2.0);
  const double got = composite_over(f, Rgb::Constant(I0)).at(0, 0, 0);
  EXPECT_NEAR(got, expected, kFloatTolerance * expected);
  EXPECT_EQ(f.stats.samples, 32);
  EXPECT_EQ(centre_value(f), 0.0);  // absorption has no source
}

TEST(VolumeIntegrator, AbsorptionSlabErrorIsBelowOneStepOtherwise) {
  const double f0 = 1.0, kappa = 0.6;
  const Volume v = constant_volume(box_2_3_6(), f0);
  const double exact = std::exp(-kappa * 2.0);
  for (int n : {50, 100, 200, 400, 800}) {  // Δs = 7/n: the path is not whole steps
    VolumeRenderSettings s = plain(OpticalModel::kAbsorption, n);
    s.kappa = kappa;
    const double ds = 7.0 / n;
    const double T = centre_T(render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s));
    // The source's loop (t < t1) counts the last, partial step in full: the path is over-counted
    // by less than one step, so exact · e^{-σΔs} < T <= exact (O(Δs), not monotone in n).
    EXPECT_LE(T, exact * (1 + kFloatTolerance)) << n;
    EXPECT_GT(T, exact * std::exp(-kappa * f0 * ds)) << n;
    // Weighting the last sample by the part of its step inside the box makes it exact again.
    s.include_last_partial = true;
    EXPECT_NEAR(centre_T(render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s)), exact, kFloatTolerance * exact)
        << n;
  }
}

TEST(VolumeIntegrator, EmissionSlabWithAndWithoutTheStep) {
  const double f0 = 0.25, gamma = 1.0;
  const Volume v = constant_volume(box_2_3_6(), f0);
  VolumeRenderSettings s = plain(OpticalModel::kEmission, 7 * 8);  // Δs = 1/8: 16 samples over ℓ = 2
  s.emission = Rgb(0.5, 1.0, 2.0);
  s.gamma = gamma;
  const VolumeFrame f = render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre_value(f, c), s.emission[c] * f0 * 2.0, kFloatTolerance);
  EXPECT_EQ(centre_T(f), 1.0);     // nothing is attenuated
  s.emission_scale_by_ds = false;  // the source's listing: no Δs, I0 + N_s C f0^γ
  const VolumeFrame g = render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s);
  EXPECT_EQ(g.stats.samples, 16);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(centre_value(g, c), 16 * s.emission[c] * f0, kFloatTolerance * 16);
}

TEST(VolumeIntegrator, EmissionAbsorptionSlabMatchesTheDiscreteFormAndConvergesToTheContinuousOne) {
  const double f0 = 0.8, kappa = 0.9, C = 1.5;
  const Volume v = constant_volume(box_2_3_6(), f0);
  const double sigma = kappa * f0, g = C * f0, ell = 2.0;
  std::vector<double> err;
  for (int m : {3, 4, 5, 6}) {  // Δs = 2^-m, N = 2^(m+1) steps
    VolumeRenderSettings s = plain(OpticalModel::kEmissionAbsorption, 7 << m);
    s.kappa = kappa;
    s.emission = Rgb::Constant(C);
    const VolumeFrame f = render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s);
    const double h = std::ldexp(1.0, -m);
    const int N = 2 << m;
    const double discrete = g * h * std::exp(-sigma * h) * (1 - std::exp(-sigma * N * h)) / (1 - std::exp(-sigma * h));
    EXPECT_NEAR(centre_value(f), discrete, kFloatTolerance * discrete) << m;
    EXPECT_NEAR(centre_T(f), std::exp(-sigma * ell), kFloatTolerance) << m;
    const double continuous = g / sigma * (1 - std::exp(-sigma * ell));
    err.push_back(std::abs(centre_value(f) - continuous));
  }
  for (std::size_t i = 0; i + 1 < err.size(); ++i) EXPECT_NEAR(err[i] / err[i + 1], 2.0, 0.2) << i;  // first order
}

TEST(VolumeIntegrator, ExponentialQuadratureIsExactForAHomogeneousSlab) {
  const double f0 = 0.8, kappa = 0.9, C = 1.5;
  const Volume v = constant_volume(box_2_3_6(), f0);
  VolumeRenderSettings s = plain(OpticalModel::kEmissionAbsorption, 37);  // not whole steps
  s.kappa = kappa;
  s.emission = Rgb::Constant(C);
  s.quadrature = Quadrature::kExponential;
  s.include_last_partial = true;
  const VolumeFrame f = render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s);
  const double sigma = kappa * f0, continuous = C * f0 / sigma * (1 - std::exp(-sigma * 2.0));
  EXPECT_NEAR(centre_value(f), continuous, kFloatTolerance * continuous);
  EXPECT_NEAR(centre_T(f), std::exp(-sigma * 2.0), kFloatTolerance);
}

// ---- target 5: the HG phase function -----------------------------------------------------------

TEST(VolumeIntegrator, HenyeyGreensteinIsNormalisedWithMeanCosineC) {
  using boost::math::quadrature::gauss_kronrod;
  for (double c = -0.9; c <= 0.9 + 1e-12; c += 0.1) {
    const double norm = gauss_kronrod<double, 61>::integrate(
        [&](double mu) { return 2 * std::numbers::pi * henyey_greenstein(mu, c); }, -1.0, 1.0, 15, 1e-12);
    const double mean = gauss_kronrod<double, 61>::integrate(
        [&](double mu) { return 2 * std::numbers::pi * mu * henyey_greenstein(mu, c); }, -1.0, 1.0, 15, 1e-12);
    EXPECT_NEAR(norm, 1.0, 1e-6) << c;
    EXPECT_NEAR(mean, c, 1e-6) << c;
  }
  EXPECT_NEAR(henyey_greenstein(0.3, 0.0), 1 / (4 * std::numbers::pi), 1e-15);
  // p(ω, ω') depends on ω·ω' only, so it is symmetric in its two directions.
  EXPECT_EQ(henyey_greenstein(0.37, 0.5), henyey_greenstein(0.37, 0.5));
}

// ---- targets 6, 7: single scattering -----------------------------------------------------------

TEST(VolumeIntegrator, UnshadowedSingleScatterMatchesItsClosedForm) {
  const double f0 = 0.6, kappa = 0.7, a = 0.9, c = 0.4, ell = 2.0;
  const Volume v = constant_volume(box_2_3_6(), f0);
  VolumeLight light;
  light.type = LightType::kDirectional;
  light.to_light = Vec3(0.3, 0.2, 1.0).normalized();
  light.intensity = Rgb(1.0, 0.5, 2.0);
  for (bool kappa_in_brdf : {false, true}) {
    VolumeRenderSettings s = plain(OpticalModel::kHG, 101);
    s.kappa = kappa;
    s.albedo = a;
    s.hg_c = c;
    s.emission = Rgb::Zero();
    s.lights = {light};
    s.kappa_in_brdf = kappa_in_brdf;
    s.quadrature = Quadrature::kExponential;  // exact for a homogeneous slab
    s.include_last_partial = true;
    const Vec3 ray_dir = Vec3::UnitX();
    const VolumeFrame f = render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s);
    const double sigma = kappa * f0, beta = kappa_in_brdf ? kappa * f0 : f0;
    const double p = henyey_greenstein(light.to_light.dot(ray_dir), c);
    for (int ch = 0; ch < 3; ++ch) {
      const double expected = a * p * light.intensity[ch] * beta / sigma * (1 - std::exp(-sigma * ell));
      EXPECT_NEAR(centre_value(f, ch), expected, kFloatTolerance * expected) << kappa_in_brdf << ch;
    }
  }
}

TEST(VolumeIntegrator, AmbientInScatterMatchesItsClosedForm) {
  // A uniform ambient radiance A in-scattered with ∫ p dω = 1, unshadowed, κ in the BRDF:
  // I = a A (1 - e^{-σ ℓ}) through a homogeneous slab; the exponential rule is exact for it.
  const double f0 = 0.7, kappa = 0.5, a = 0.85;
  const Volume v = constant_volume(box_2_3_6(), f0);
  VolumeRenderSettings s = plain(OpticalModel::kHG, 53);
  s.kappa = kappa;
  s.albedo = a;
  s.emission = Rgb::Zero();
  VolumeLight dark;
  dark.type = LightType::kDirectional;
  dark.intensity = Rgb::Zero();
  s.lights = {dark};
  s.ambient = Rgb(0.2, 0.4, 0.8);
  s.kappa_in_brdf = true;
  s.quadrature = Quadrature::kExponential;
  s.include_last_partial = true;
  const VolumeFrame f = render_volume(v, one_ray(Vec3(-10, 0, 0), Vec3(0, 0, 0)), s);
  for (int ch = 0; ch < 3; ++ch) {
    const double expected = a * s.ambient[ch] * (1 - std::exp(-kappa * f0 * 2.0));
    EXPECT_NEAR(centre_value(f, ch), expected, kFloatTolerance * expected) << ch;
  }
}

// A point light near a homogeneous slab: the phase angle and the inverse-square falloff change
// along the ray. The exponential rule with a midpoint sample per step against Gauss–Kronrod
// quadrature of the same integral, written independently:
//   I = ∫ a e p_HG(cos θ(t)) L / r(t)² e^{-σ (t - t0)} dt,  cos θ = (x - L)/|x - L| · (-v).
TEST(VolumeIntegrator, PointLightScatteringMatchesQuadratureOfTheSameIntegral) {
  using boost::math::quadrature::gauss_kronrod;
  const double f0 = 0.5, kappa = 0.3, a = 0.8, c = 0.6;
  const Volume v = constant_volume(box_2_3_6(), f0);
  VolumeLight light;
  light.type = LightType::kPoint;
  light.position = Vec3(0.3, 2.5, 0.4);  // beside the ray, close enough for p and 1/r² to vary a lot
  light.intensity = Rgb(2.0, 1.0, 0.5);
  light.falloff = LightFalloff::kInverseSquare;
  VolumeRenderSettings s = plain(OpticalModel::kHG, 7 * 512);  // Δs = 1/512
  s.kappa = kappa;
  s.albedo = a;
  s.hg_c = c;
  s.emission = Rgb::Zero();
  s.lights = {light};
  s.quadrature = Quadrature::kExponential;
  s.first_offset = FirstOffset::kHalf;
  const Vec3 eye(-10, 0, 0), dir = Vec3::UnitX();
  const VolumeFrame f = render_volume(v, one_ray(eye, Vec3(0, 0, 0)), s);
  const double sigma = kappa * f0, t0 = 9.0, t1 = 11.0;
  const double expected = gauss_kronrod<double, 61>::integrate(
      [&](double t) {
        const Vec3 x = eye + t * dir;
        const Vec3 from_light = x - light.position;
        const double r2 = from_light.squaredNorm();
        const double cos_theta = -(from_light / std::sqrt(r2)).dot(dir);
        return a * f0 * henyey_greenstein(cos_theta, c) / r2 * std::exp(-sigma * (t - t0));
      },
      t0, t1, 15, 1e-12);
  // Midpoint sampling of a smooth integrand: error O(Δs²) ~ 1e-6 of the value here.
  for (int ch = 0; ch < 3; ++ch)
    EXPECT_NEAR(centre_value(f, ch), light.intensity[ch] * expected, 1e-5 * light.intensity[ch] * expected) << ch;
}

// The shadowed slab of target 7: a wide box of thickness H seen straight down at its centre, a
// directional light from above at polar angle θ; every shadow ray leaves through the top.
struct ShadowedSlab {
  double H = 1.0, kappa = 1.0, a = 0.8, c = 0.3, theta = std::numbers::pi / 4, half_width = 2.0;
  Box3 box() const { return Box3{Vec3(-half_width, -half_width, -H / 2), Vec3(half_width, half_width, H / 2)}; }
  VolumeLight light() const {
    VolumeLight l;
    l.type = LightType::kDirectional;
    l.to_light = Vec3(std::sin(theta), 0, std::cos(theta));
    return l;
  }
  double exact() const {
    const double mu = std::cos(theta), k = 1 + 1 / mu;
    return a * henyey_greenstein(-mu, c) * (1 - std::exp(-kappa * H * k)) / k;  // β = σ (κ in the BRDF)
  }
  VolumeRenderSettings settings(int n) const {
    VolumeRenderSettings s = plain(OpticalModel::kHGAttenuated, n);
    s.kappa = kappa;
    s.albedo = a;
    s.hg_c = c;
    s.emission = Rgb::Zero();
    s.lights = {light()};
    s.kappa_in_brdf = true;
    return s;
  }
  double render(const VolumeRenderSettings& s) const {
    const Volume v = constant_volume(box(), 1.0);
    return render_volume(v, one_ray(Vec3(0, 0, 10), Vec3(0, 0, 0), Vec3::UnitY()), s).radiance.at(0, 0, 0);
  }
};

TEST(VolumeIntegrator, ShadowedSingleScatterMatchesItsClosedFormWithinOnePercentAtN256) {
  const ShadowedSlab slab;
  ASSERT_GT(slab.half_width, slab.H * std::tan(slab.theta));
  const double exact = slab.exact();
  EXPECT_LT(std::abs(slab.render(slab.settings(256)) - exact) / exact, 0.01);  // the spec's defaults
  // First order: with the last partial step weighted (so the path is covered exactly whatever
  // Δs), halving Δs halves the error.
  std::vector<double> err;
  for (int n : {256, 512, 1024, 2048}) {
    VolumeRenderSettings s = slab.settings(n);
    s.include_last_partial = true;
    err.push_back(std::abs(slab.render(s) - exact) / exact);
  }
  for (std::size_t i = 0; i + 1 < err.size(); ++i) EXPECT_NEAR(err[i] / err[i + 1], 2.0, 0.2) << i;
}

TEST(VolumeIntegrator, ShadowCacheMatchesTheMarchOnAHomogeneousSlab) {
  const ShadowedSlab slab;
  VolumeRenderSettings s = slab.settings(256);
  const double march = slab.render(s);
  s.shadow = ShadowMethod::kCache;
  for (auto build : {ShadowCacheBuild::kMarch, ShadowCacheBuild::kSweep}) {
    s.shadow_cache_build = build;
    // The cache holds T at the volume's samples and is interpolated trilinearly: exact along the
    // layers of a homogeneous slab but for the curvature of exp(-σ z/μ) between samples
    // (σ h / μ = 0.18 per sample here: a relative error of order (σh/μ)²/8 ≈ 0.4 %).
    EXPECT_NEAR(slab.render(s), march, 0.01 * march) << int(build);
  }
}

// ---- targets 14, 15 and the integrator's promises ---------------------------------------------

Volume turbulence(VolumeKind kind, int n, const Box3& box) {
  VolumeGenerateOptions g;
  g.kind = kind;
  g.nx = g.ny = g.nz = n;
  Volume v = generate_volume(g);
  v.fit_to_box(box);
  return v;
}

Box3 box300() { return Box3{Vec3::Constant(-150), Vec3::Constant(150)}; }
Camera camera_64() { return Pinhole::look_at(64, 48, 60.0, Vec3(420, -520, 300), Vec3(0, 0, 0), Vec3::UnitZ()); }

VolumeRenderSettings cloud(OpticalModel model) {
  VolumeRenderSettings s;
  s.model = model;
  s.samples = 64;
  s.kappa = 0.02;
  s.emission = Rgb(0.02, 0.015, 0.01);
  return s;
}

TEST(VolumeIntegrator, TwoPassRaysEqualTheAnalyticOnesOnInteriorPixels) {
  const Box3 box = box300();
  const Camera cam = Pinhole::look_at(96, 80, 70.0, Vec3(430, -510, 290), Vec3(5, 3, -2), Vec3::UnitZ());
  const TwoPassRays tp = two_pass_rays(box, cam);
  const RayGenerator gen(cam);
  auto covered = [&](int x, int y) {
    const std::size_t p = std::size_t(y) * std::size_t(tp.width) + std::size_t(x);
    return tp.front[p] && tp.back[p];
  };
  int interior = 0, silhouette_only = 0;
  for (int y = 0; y < tp.height; ++y)
    for (int x = 0; x < tp.width; ++x) {
      const std::size_t p = std::size_t(y) * std::size_t(tp.width) + std::size_t(x);
      const CameraRay ray = gen.generate_ray(x, y);
      const auto hit = intersect_box(box, ray.origin, ray.direction);
      bool border = x == 0 || y == 0 || x + 1 == tp.width || y + 1 == tp.height;
      for (int dy = -1; dy <= 1 && !border; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (!covered(x + dx, y + dy)) border = true;
      if (border) {
        if (bool(hit) != covered(x, y)) ++silhouette_only;
        continue;
      }
      ASSERT_TRUE(hit) << x << "," << y;
      ++interior;
      EXPECT_LT((tp.entry[p] - ray.at(hit->t0)).norm(), 1e-9 * box.diagonal()) << x << "," << y;
      EXPECT_LT((tp.exit[p] - ray.at(hit->t1)).norm(), 1e-9 * box.diagonal()) << x << "," << y;
    }
  EXPECT_GT(interior, 1000);
  // Rendered both ways, interior pixels agree to float rounding of the sample positions.
  const Volume v = turbulence(VolumeKind::kTurbulenceBox, 32, box);
  VolumeRenderSettings s = cloud(OpticalModel::kEmissionAbsorption);
  const VolumeFrame a = render_volume(v, cam, s);
  s.ray_generation = RayGeneration::kTwoPass;
  const VolumeFrame b = render_volume(v, cam, s);
  double max_rel = 0;
  for (int y = 1; y + 1 < tp.height; ++y)
    for (int x = 1; x + 1 < tp.width; ++x) {
      bool all = true;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) all = all && covered(x + dx, y + dy);
      if (!all) continue;
      const double ra = a.radiance.at(x, y, 0), rb = b.radiance.at(x, y, 0);
      max_rel = std::max(max_rel, std::abs(ra - rb) / std::max(1e-12, std::abs(ra)));
    }
  // Sample positions differ by the rounding of eye + t v against F_f + s v (~1e-13 of the box):
  // trilinear values move by that times the field's gradient; the sum stays within 1e-5.
  EXPECT_LT(max_rel, 1e-5);
}

TEST(VolumeIntegrator, ZeroDensityLeavesTheBackgroundBitExact) {
  const Volume v = constant_volume(box300(), 0.0);
  for (auto model : {OpticalModel::kAbsorption, OpticalModel::kEmission, OpticalModel::kEmissionAbsorption,
                     OpticalModel::kHG, OpticalModel::kHGAttenuated}) {
    VolumeRenderSettings s = cloud(model);
    const VolumeFrame f = render_volume(v, camera_64(), s);
    const Rgb bg(0.3, 0.123456, 0.9);
    const ImageF out = composite_over(f, bg);
    for (int y = 0; y < out.height(); ++y)
      for (int x = 0; x < out.width(); ++x)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(out.at(x, y, c), float(bg[c])) << optical_model_name(model);
  }
}

TEST(VolumeIntegrator, CompositeIsRadiancePlusTransmittanceTimesTheBackground) {
  const Volume v = turbulence(VolumeKind::kTurbulenceSphere, 24, box300());
  const VolumeFrame f = render_volume(v, camera_64(), cloud(OpticalModel::kEmissionAbsorption));
  ImageF bg(64, 48, 3);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c) bg.at(x, y, c) = float(((x / 8 + y / 8) % 2) * 0.5 + 0.1 * c);
  const ImageF out = composite_over(f, bg);
  int attenuated = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      if (f.transmittance.at(x, y) < 1) ++attenuated;
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(out.at(x, y, c), f.radiance.at(x, y, c) + f.transmittance.at(x, y) * bg.at(x, y, c));
    }
  EXPECT_GT(attenuated, 200);
}

bool same(const ImageF& a, const ImageF& b) { return a == b; }

TEST(VolumeIntegrator, SerialAndParallelRendersAreBitwiseEqual) {
  const Volume v = turbulence(VolumeKind::kTurbulenceBox, 24, box300());
  for (auto model : {OpticalModel::kEmission, OpticalModel::kHG, OpticalModel::kHGAttenuated}) {
    VolumeRenderSettings s = cloud(model);
    s.samples = 32;
    s.first_offset = FirstOffset::kJitter;
    s.parallel = true;
    const VolumeFrame p = render_volume(v, camera_64(), s);
    s.parallel = false;
    const VolumeFrame q = render_volume(v, camera_64(), s);
    EXPECT_TRUE(same(p.radiance, q.radiance)) << optical_model_name(model);
    EXPECT_TRUE(same(p.transmittance, q.transmittance)) << optical_model_name(model);
    EXPECT_EQ(p.stats.samples, q.stats.samples);
  }
}

TEST(VolumeIntegrator, EmptySpaceSkippingChangesNoPixel) {
  const Volume v = turbulence(VolumeKind::kTurbulenceSphere, 32, box300());
  for (auto model : {OpticalModel::kEmissionAbsorption, OpticalModel::kHGAttenuated}) {
    VolumeRenderSettings s = cloud(model);
    s.skip_empty = true;
    const VolumeFrame a = render_volume(v, camera_64(), s);
    s.skip_empty = false;
    const VolumeFrame b = render_volume(v, camera_64(), s);
    EXPECT_TRUE(same(a.radiance, b.radiance)) << optical_model_name(model);
    EXPECT_TRUE(same(a.transmittance, b.transmittance));
    EXPECT_GT(a.stats.skipped, 0);
    EXPECT_LT(a.stats.samples, b.stats.samples);
    EXPECT_EQ(a.stats.samples + a.stats.skipped, b.stats.samples);
  }
}

// A sparse volume — a few small blobs far apart in 96³ — where rays cross long runs of dead
// macrocells, several at a time by the chessboard distance: the jumps must not cross a live one
// (every pixel and the sample count equal to marching without skipping), for each model and the
// shadow march (which skips on the same macrocells).
TEST(VolumeIntegrator, EmptySpaceJumpsAcrossSparseVolumesChangeNoPixel) {
  Volume v = Volume::allocate(96, 96, 96, SampleType::kFloat32);
  const int blobs[][3] = {{5, 7, 9}, {48, 50, 47}, {90, 12, 80}, {20, 88, 60}, {70, 70, 3}, {94, 94, 94}};
  for (const auto& b : blobs)
    for (int k = -2; k <= 2; ++k)
      for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) {
          const int x = b[0] + i, y = b[1] + j, z = b[2] + k;
          if (x >= 0 && y >= 0 && z >= 0 && x < 96 && y < 96 && z < 96) v.set_value(x, y, z, 1.0 + 0.1 * (i + j + k));
        }
  v.fit_to_box(box300());
  const Camera cam = Pinhole::look_at(80, 64, 70.0, Vec3(420, -520, 300), Vec3(0, 0, 0), Vec3::UnitZ());
  for (auto model : {OpticalModel::kEmission, OpticalModel::kEmissionAbsorption, OpticalModel::kHGAttenuated}) {
    VolumeRenderSettings s = cloud(model);
    s.samples = 300;  // a step of ~1.7 voxels: samples land in the blobs
    s.kappa = 0.05;
    s.skip_empty = true;
    const VolumeFrame a = render_volume(v, cam, s);
    s.skip_empty = false;
    const VolumeFrame b = render_volume(v, cam, s);
    EXPECT_TRUE(same(a.radiance, b.radiance)) << optical_model_name(model);
    EXPECT_TRUE(same(a.transmittance, b.transmittance)) << optical_model_name(model);
    EXPECT_EQ(a.stats.samples + a.stats.skipped, b.stats.samples);
    EXPECT_GT(a.stats.skipped, 20 * a.stats.samples);  // nearly everything is empty
    double lit = 0;
    for (float x : b.radiance.values()) lit += double(x);
    EXPECT_GT(lit, 0.0) << "the blobs must be seen, or the comparison says nothing";
  }
}

// A dense volume with a few empty holes (a cube off the centre, a slab on one face, a single
// macrocell): the live runs reach across many live macrocells at once and must stop at the faces of
// the cubes around the holes; the dead ones jump only inside the holes. Every pixel and the sample
// count equal marching without skipping, for each model and the shadow march.
TEST(VolumeIntegrator, LiveRunsAcrossDenseVolumesStopAtTheHoles) {
  Volume v = turbulence(VolumeKind::kTurbulenceBox, 64, box300());
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        const bool cube = i >= 36 && i < 52 && j >= 20 && j < 36 && k >= 30 && k < 46;
        const bool slab = k < 6;
        const bool cell = i >= 8 && i < 16 && j >= 44 && j < 52 && k >= 12 && k < 20;
        if (cube || slab || cell) v.set_value(i, j, k, 0.0);
      }
  for (auto model : {OpticalModel::kEmission, OpticalModel::kEmissionAbsorption, OpticalModel::kHGAttenuated}) {
    VolumeRenderSettings s = cloud(model);
    s.samples = 160;
    s.first_offset = FirstOffset::kJitter;
    s.skip_empty = true;
    const VolumeFrame a = render_volume(v, camera_64(), s);
    s.skip_empty = false;
    const VolumeFrame b = render_volume(v, camera_64(), s);
    EXPECT_TRUE(same(a.radiance, b.radiance)) << optical_model_name(model);
    EXPECT_TRUE(same(a.transmittance, b.transmittance)) << optical_model_name(model);
    EXPECT_EQ(a.stats.samples + a.stats.skipped, b.stats.samples) << optical_model_name(model);
    EXPECT_GT(a.stats.skipped, 0) << "the holes must be crossed, or the comparison says nothing";
  }
}

TEST(VolumeIntegrator, EarlyRayTerminationStaysWithinItsBound) {
  const Volume v = turbulence(VolumeKind::kTurbulenceBox, 24, box300());
  VolumeRenderSettings s = cloud(OpticalModel::kEmissionAbsorption);
  s.kappa = 0.2;  // opaque: most rays terminate
  const VolumeFrame full = render_volume(v, camera_64(), s);
  s.ert_transmittance = 1e-3;
  const VolumeFrame ert = render_volume(v, camera_64(), s);
  EXPECT_GT(ert.stats.terminated, 100);
  EXPECT_LT(ert.stats.samples, full.stats.samples);
  // What a terminated ray leaves out is at most T_stop · Σ_rest g Δs <= T_stop · C · (path length).
  const double bound = 1e-3 * s.emission.maxCoeff() * box300().diagonal();
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      ASSERT_LE(std::abs(full.radiance.at(x, y, 0) - ert.radiance.at(x, y, 0)), bound);
      ASSERT_LE(ert.transmittance.at(x, y), std::max(1e-3f, full.transmittance.at(x, y) * 1.0001f) + 1e-7f);
    }
}

TEST(VolumeIntegrator, ShadowCacheIsCloseToTheExactMarchOnTurbulence) {
  const Volume v = turbulence(VolumeKind::kTurbulenceSphere, 32, box300());
  VolumeRenderSettings s = cloud(OpticalModel::kHGAttenuated);
  s.emission = Rgb::Zero();
  const VolumeFrame march = render_volume(v, camera_64(), s);
  s.shadow = ShadowMethod::kCache;
  double sum2 = 0, ref2 = 0;
  const VolumeFrame cache = render_volume(v, camera_64(), s);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const double d = cache.radiance.at(x, y, 0) - march.radiance.at(x, y, 0);
      sum2 += d * d;
      ref2 += double(march.radiance.at(x, y, 0)) * double(march.radiance.at(x, y, 0));
    }
  // The cache interpolates T between the volume's samples: on a 32³ turbulence the image differs
  // from the exact march by well under 2 % (relative RMS).
  EXPECT_LT(std::sqrt(sum2 / ref2), 0.02);
  EXPECT_LT(cache.stats.shadow_samples, march.stats.shadow_samples / 5);
}

TEST(VolumeIntegrator, RefusesAnEyeInsideTheBoxUnlessAskedToStartThere) {
  const Volume v = constant_volume(box300(), 0.1);
  const Camera inside = Pinhole::look_at(8, 8, 8.0, Vec3(10, 0, 0), Vec3(100, 0, 0), Vec3::UnitZ());
  VolumeRenderSettings s = cloud(OpticalModel::kAbsorption);
  EXPECT_THROW(render_volume(v, inside, s), InputError);
  s.camera_inside = CameraInside::kStartAtEye;
  s.kappa = 0.01;
  const VolumeFrame f = render_volume(v, inside, s);
  // The centre ray runs from x = 10 to the face x = 150: T = exp(-κ f ℓ), ℓ = 140 (to the step).
  EXPECT_NEAR(f.transmittance.at(4, 4), std::exp(-0.01 * 0.1 * 140), 0.01);
}

TEST(VolumeIntegrator, RefusesBadSettings) {
  const Volume v = constant_volume(box300(), 0.1);
  auto expect_refused = [&](auto edit) {
    VolumeRenderSettings s = cloud(OpticalModel::kHG);
    edit(s);
    EXPECT_THROW(render_volume(v, camera_64(), s), InputError);
  };
  expect_refused([](VolumeRenderSettings& s) { s.samples = 0; });
  expect_refused([](VolumeRenderSettings& s) { s.kappa = -1; });
  expect_refused([](VolumeRenderSettings& s) { s.gamma = 0; });
  expect_refused([](VolumeRenderSettings& s) { s.hg_c = 1.0; });
  expect_refused([](VolumeRenderSettings& s) { s.ert_transmittance = 1.0; });
  expect_refused([](VolumeRenderSettings& s) {
    s.quadrature = Quadrature::kExponential;
    s.emission_scale_by_ds = false;
  });
}

}  // namespace
}  // namespace meltlab::render
