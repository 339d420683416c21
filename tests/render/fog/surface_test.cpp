// The surface terms of seed 002 (G_n tables, render/fog/fog_tables.h, airlight.h) against the
// surface references (spec §6.7-6.8).

#include <meltlab/render/fog/airlight.h>
#include <meltlab/render/fog/airlight_f.h>
#include <meltlab/render/fog/fog_tables.h>
#include <meltlab/render/fog/quadrature.h>
#include <meltlab/render/fog/reference.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace meltlab::render::fog {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

TEST(SurfaceG, RingWeightMatchesItsDefinition) {
  // W_n(φ, θ) = ∫_0^{2π} max(0, cos φ cos θ + sin φ sin θ cos ψ)^n dψ by adaptive Gauss–Kronrod.
  for (int n : {1, 2, 5, 20})
    for (double phi : {0.0, 0.3, 1.0, 1.5, 2.0, 3.0})
      for (double theta : {0.0, 0.2, 1.0, kPi / 2, 2.5, kPi}) {
        const double a = std::cos(phi) * std::cos(theta), b = std::sin(phi) * std::sin(theta);
        // Split at the hemisphere's edge ±ψ0 (the integrand's kinks).
        const double psi0 = std::abs(b) > 0 ? std::acos(std::clamp(-a / b, -1.0, 1.0)) : kPi;
        auto g = [&](double psi) { return std::pow(std::max(0.0, a + b * std::cos(psi)), n); };
        const double ref = 2 * (integrate_gk(g, 0.0, psi0, 1e-12) + integrate_gk(g, psi0, kPi, 1e-12));
        EXPECT_NEAR(ring_weight(n, phi, theta), ref, 1e-11) << n << " " << phi << " " << theta;
      }
}

TEST(SurfaceG, ClosedFormAtZeroOpticalDepth) {
  // T = 0, θ = 0: D = π/2 - φ/2 and W_1 = 2π cos φ on [0, π/2]: G_1(0, 0) = π(π/2 + 1).
  EXPECT_NEAR(surface_g(1, 0.0, 0.0), kPi * (kPi / 2 + 1), 1e-9);
}

TEST(SurfaceG, MatchesANestedAdaptiveIntegral) {
  // The composite rule against nested adaptive Gauss–Kronrod over φ (pole at the light) and ψ.
  for (int n : {1, 20})
    for (auto [T, theta] : {std::pair{0.5, 0.4}, std::pair{3.0, 1.9}, std::pair{8.0, 0.0}}) {
      auto inner = [&](double phi) {
        const double kernel = std::exp(-T * std::cos(phi)) *
                              (airlight_f(T * std::sin(phi), kPi / 2) - airlight_f(T * std::sin(phi), phi / 2));
        const double a = std::cos(phi) * std::cos(theta), b = std::sin(phi) * std::sin(theta);
        const double psi0 = std::abs(b) > 0 ? std::acos(std::clamp(-a / b, -1.0, 1.0)) : kPi;
        auto g = [&](double psi) { return std::pow(std::max(0.0, a + b * std::cos(psi)), n); };
        return kernel * 2 * (integrate_gk(g, 0.0, psi0, 1e-11) + integrate_gk(g, psi0, kPi, 1e-11));
      };
      const double k1 = std::abs(kPi / 2 - theta), k2 = kPi - k1;
      const double ref = integrate_gk(inner, 0.0, k1, 1e-10) + integrate_gk(inner, k1, k2, 1e-10) +
                         integrate_gk(inner, k2, kPi, 1e-10);
      EXPECT_NEAR(surface_g(n, T, theta), ref, 1e-7 * ref) << "n " << n << " T " << T << " θ " << theta;
    }
}

TEST(SurfaceG, TableRowsEqualSingleValues) {
  TableOptions o;
  o.n = 9;
  const FogTable g = g_table(20, o);
  for (int i : {0, 3, 8})
    for (int j : {0, 4, 7}) EXPECT_NEAR(g.values.at(i, j), surface_g(20, g.x.node(i), g.y.node(j)), 1e-6);
}

struct SurfaceCase {
  Vec3 p, normal, eye;
  double kt;
};

TEST(SurfaceTerms, ExactGEqualsRSurfModel) {
  // The G-based scattered term with the accurate G against the hemisphere quadrature of R-air:
  // both sides evaluate eq. 3.19 under the same assumptions, so they agree to the reference's
  // convergence (1e-6) plus G's 1e-7.
  Spotlight light;
  light.position = Vec3(0.5, -0.3, 3);
  light.axis = Vec3(0, 0, -1);
  light.profile = {ConeStep{40 * kDeg, 1.0}};
  const FogMaterial mat{0.7, 0.3, 20, Rgb(1, 1, 1)};
  for (const SurfaceCase& c : {SurfaceCase{Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, -4, 2), 0.1},
                               SurfaceCase{Vec3(0.4, 0.2, 0.1), Vec3(0.6, 0, 0.8), Vec3(3, -3, 1), 0.5}}) {
    FogMedium med;
    med.kt = c.kt;
    const Vec3 view = (c.p - c.eye).normalized();
    const SurfaceTerms model = surface_terms(c.p, c.normal, view, light, med, mat, FogFunctions{}, FogModelOptions{});
    SurfRefOptions ro;
    ro.rel_change = 1e-5;
    ro.max_n_phi = 512;
    const SurfRefResult ref = r_surf_model(c.p, c.normal, view, light, med, mat, FogModelOptions{}, ro);
    EXPECT_NEAR(model.fog_diffuse, ref.terms.fog_diffuse, 1e-4 * ref.terms.fog_diffuse);
    EXPECT_NEAR(model.fog_specular, ref.terms.fog_specular, 1e-4 * ref.terms.fog_specular);
    EXPECT_DOUBLE_EQ(model.direct_diffuse, ref.terms.direct_diffuse);
  }
}

TEST(SurfaceTerms, ZeroExtinctionIsPlainPhong) {
  Spotlight light;
  light.position = Vec3(1, 1, 4);
  light.axis = Vec3(0, 0, -1);
  light.profile = {ConeStep{50 * kDeg, 1.0}};
  FogMedium med;
  med.kt = 0;
  const FogMaterial mat{0.7, 0.3, 20, Rgb(1, 1, 1)};
  const Vec3 p(0.2, 0.1, 0), n(0, 0, 1), eye(0, -3, 2);
  const Vec3 view = (p - eye).normalized();
  const SurfaceTerms s = surface_terms(p, n, view, light, med, mat, FogFunctions{}, FogModelOptions{});
  const Vec3 L = (light.position - p).normalized();
  const double l2 = (light.position - p).squaredNorm();
  const Vec3 R = view - 2 * view.dot(n) * n;
  EXPECT_DOUBLE_EQ(s.diffuse(), 0.7 * n.dot(L) / l2);
  EXPECT_NEAR(s.specular(), 0.3 * std::pow(std::max(0.0, R.dot(L)), 20) / l2, 1e-15);
  EXPECT_EQ(s.fog_diffuse + s.fog_specular, 0.0);
  // The whole pixel: no airlight, and the view attenuation is 1.
  const SurfaceHit hit{p, n, &mat};
  const Rgb c = fog_radiance(eye, view, (p - eye).norm(), &hit, {light}, med, FogFunctions{}, FogModelOptions{});
  EXPECT_NEAR(c.x(), s.diffuse() + s.specular(), 1e-15);
  // Outside the cone nothing (fsa.surface.only_in_cone).
  const Vec3 far_p(10, 0, 0);
  const SurfaceTerms off =
      surface_terms(far_p, n, (far_p - eye).normalized(), light, med, mat, FogFunctions{}, FogModelOptions{});
  EXPECT_EQ(off.diffuse() + off.specular(), 0.0);
}

TEST(SurfaceTerms, PointLightEqualsSpotInsideTheCone) {
  // Sun et al.'s surface terms: identical for any lit point (the cone only gates them).
  Spotlight spot;
  spot.position = Vec3(0, 0, 3);
  spot.axis = Vec3(0, 0, -1);
  spot.profile = {ConeStep{45 * kDeg, 1.0}};
  Spotlight point = spot;
  point.kind = LightKind::kPoint;
  FogMedium med;
  med.kt = 0.3;
  TableOptions o;
  o.n = 32;
  const FogTable f = f_table(o), g1 = g_table(1, o), g20 = g_table(20, o);
  const FogFunctions fn{&f, &g1, &g20};
  const FogMaterial mat;
  const Vec3 p(0.5, 0.5, 0), n(0, 0, 1), view = (p - Vec3(0, -5, 2)).normalized();
  const SurfaceTerms a = surface_terms(p, n, view, spot, med, mat, fn, FogModelOptions{});
  const SurfaceTerms b = surface_terms(p, n, view, point, med, mat, fn, FogModelOptions{});
  EXPECT_EQ(a.diffuse(), b.diffuse());
  EXPECT_EQ(a.specular(), b.specular());
  EXPECT_GT(a.fog_diffuse, 0.0);
}

}  // namespace
}  // namespace meltlab::render::fog
