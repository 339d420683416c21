// Dielectric optics (material/optics.h): Fresnel (Eq. 6.9), Schlick (Eq. 6.10), reflection (Eq. 6.3),
// refraction with total internal reflection (Eq. 6.7) and dispersion (Eq. 6.8).

#include <meltlab/render/material/optics.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace meltlab::render {
namespace {

using V3 = Eigen::Vector3d;
constexpr double kTol = 1e-12;  // closed forms in double precision
// Largest |Schlick - full| over all angles, measured with a 10^4-step sweep of cos Θ (see the
// test): 0.0653 for air/ice, 0.0357 for η = 1.5. The bounds leave 5 % for the sweep's step.
constexpr double kSchlickErrIce = 0.069;
constexpr double kSchlickErrGlass = 0.038;

V3 from_angle(double theta) { return V3(std::sin(theta), 0.0, -std::cos(theta)); }  // incident, N = +z

TEST(Fresnel, NormalIncidenceIsSquaredIndexContrast) {
  for (double n2 : {1.0, 1.31, 1.3079, 1.5, 2.2}) {
    const double want = std::pow((1.0 - n2) / (1.0 + n2), 2);
    EXPECT_NEAR(fresnel_dielectric(1.0, 1.0, n2), want, kTol) << n2;
    EXPECT_NEAR(fresnel_dielectric(1.0, n2, 1.0), want, kTol) << n2;  // symmetric at normal incidence
    EXPECT_NEAR(fresnel_schlick(1.0, 1.0, n2), want, kTol) << n2;
  }
  // The spec's derived value for air/ice.
  EXPECT_NEAR(fresnel_dielectric(1.0, 1.0, kIceEta), 0.0180, 1e-4);
}

TEST(Fresnel, EqualsMeanOfSAndPPolarisation) {
  // Eq. 6.9 is the unpolarised mean of the textbook Rs and Rp.
  for (double theta = 0.0; theta < 1.55; theta += 0.05) {
    const double n1 = 1.0, n2 = kIceEta;
    const double ci = std::cos(theta), st = n1 / n2 * std::sin(theta), ct = std::sqrt(1 - st * st);
    const double rs = std::pow((n1 * ci - n2 * ct) / (n1 * ci + n2 * ct), 2);
    const double rp = std::pow((n1 * ct - n2 * ci) / (n1 * ct + n2 * ci), 2);
    EXPECT_NEAR(fresnel_dielectric(ci, n1, n2), 0.5 * (rs + rp), 1e-12) << theta;
  }
}

TEST(Fresnel, TendsToOneAtGrazingAndIsMonotonic) {
  EXPECT_NEAR(fresnel_dielectric(0.0, 1.0, kIceEta), 1.0, kTol);
  EXPECT_GT(fresnel_dielectric(1e-3, 1.0, kIceEta), 0.98);
  EXPECT_NEAR(fresnel_schlick(0.0, 1.0, kIceEta), 1.0, kTol);
  double prev = 0.0;
  for (int i = 1000; i >= 0; --i) {  // cos from 1 down to 0: reflectance rises
    const double f = fresnel_dielectric(i / 1000.0, 1.0, kIceEta);
    EXPECT_GE(f, prev - 1e-15) << i;
    prev = f;
  }
}

TEST(Fresnel, TotalInternalReflectionInsideIce) {
  const double critical = std::asin(1.0 / kIceEta);  // ≈ 49.8°
  EXPECT_EQ(fresnel_dielectric(std::cos(critical + 0.01), kIceEta, 1.0), 1.0);
  EXPECT_EQ(fresnel_schlick(std::cos(critical + 0.01), kIceEta, 1.0), 1.0);
  EXPECT_LT(fresnel_dielectric(std::cos(critical - 0.05), kIceEta, 1.0), 1.0);
  // Just below the critical angle the reflectance climbs steeply towards 1.
  EXPECT_GT(fresnel_dielectric(std::cos(critical - 1e-6), kIceEta, 1.0), 0.95);
  // Reciprocity: reflectance is the same from either side for the matching pair of angles.
  const double ti = 0.6, tt = std::asin(std::sin(ti) / kIceEta);
  EXPECT_NEAR(fresnel_dielectric(std::cos(ti), 1.0, kIceEta), fresnel_dielectric(std::cos(tt), kIceEta, 1.0), 1e-12);
}

TEST(Schlick, WithinItsKnownErrorOfTheFullFormula) {
  double max_ice = 0, max_glass = 0;
  for (int i = 0; i <= 10000; ++i) {
    const double c = i / 10000.0;
    max_ice = std::max(max_ice, std::abs(fresnel_schlick(c, 1.0, kIceEta) - fresnel_dielectric(c, 1.0, kIceEta)));
    max_ice = std::max(max_ice, std::abs(fresnel_schlick(c, kIceEta, 1.0) - fresnel_dielectric(c, kIceEta, 1.0)));
    max_glass = std::max(max_glass, std::abs(fresnel_schlick(c, 1.0, 1.5) - fresnel_dielectric(c, 1.0, 1.5)));
  }
  EXPECT_LE(max_ice, kSchlickErrIce);
  EXPECT_LE(max_glass, kSchlickErrGlass);
  // The monograph's remark: ice lies outside Schlick's good range; its error is larger there.
  EXPECT_GT(max_ice, max_glass);
  EXPECT_GT(max_ice, 0.05);  // and not negligible: the approximation is really different
}

TEST(Reflect, MirrorsAboutTheNormal) {
  const V3 n(0, 0, 1);
  const V3 v = V3(0.3, -0.4, 0.8).normalized();
  const V3 r = reflect(v, n);
  EXPECT_NEAR(r.x(), -v.x(), kTol);
  EXPECT_NEAR(r.y(), -v.y(), kTol);
  EXPECT_NEAR(r.z(), v.z(), kTol);
  EXPECT_NEAR(r.norm(), 1.0, kTol);
}

TEST(Refract, ObeysSnellsLawAndBendsTowardsTheNormal) {
  const V3 n(0, 0, 1);
  for (double theta : {0.0, 0.2, 0.7, 1.2, 1.5}) {
    const auto t = refract(from_angle(theta), n, 1.0 / kIceEta);
    ASSERT_TRUE(t.has_value()) << theta;
    EXPECT_NEAR(t->norm(), 1.0, kTol);
    EXPECT_LT(t->z(), 0.0);  // goes into the ice
    const double sin_t = std::hypot(t->x(), t->y());
    EXPECT_NEAR(1.0 * std::sin(theta), kIceEta * sin_t, 1e-12) << theta;  // Eq. 6.6
    EXPECT_GE(t->x(), 0.0);                                               // stays in the plane of incidence, same side
  }
}

TEST(Refract, TotalInternalReflectionBranch) {
  const V3 n(0, 0, 1);  // leaving ice upwards: incident goes +z, normal faces the incident side
  const V3 n_in(0, 0, -1);
  const double critical = std::asin(1.0 / kIceEta);
  const V3 below(std::sin(critical - 0.01), 0, std::cos(critical - 0.01));
  const V3 beyond(std::sin(critical + 0.01), 0, std::cos(critical + 0.01));
  EXPECT_TRUE(refract(below, n_in, kIceEta).has_value());
  EXPECT_FALSE(refract(beyond, n_in, kIceEta).has_value());
  (void)n;
  // Air to ice never reflects totally.
  EXPECT_TRUE(refract(from_angle(1.5707), V3(0, 0, 1), 1.0 / kIceEta).has_value());
}

TEST(Dispersion, BlueBendsMostThenGreenThenRed) {
  const auto eta = air_to_ice_eta_rgb();
  EXPECT_NEAR(eta[0], 0.7646, 1e-4);
  EXPECT_NEAR(eta[1], 0.7623, 1e-4);
  EXPECT_NEAR(eta[2], 0.7594, 1e-4);
  const V3 n(0, 0, 1);
  const auto t = refract_rgb(from_angle(0.8), n, eta);
  ASSERT_TRUE(t[0] && t[1] && t[2]);
  // Angle from the inward normal: shorter wavelength (larger η) refracts less far from it.
  const double ar = std::acos(-t[0]->z()), ag = std::acos(-t[1]->z()), ab = std::acos(-t[2]->z());
  EXPECT_GT(ar, ag);
  EXPECT_GT(ag, ab);
  EXPECT_GT(ar - ab, 1e-3);  // visible: ≈ 0.2° apart at 46° incidence
  // At normal incidence there is no dispersion.
  const auto t0 = refract_rgb(V3(0, 0, -1), n, eta);
  EXPECT_NEAR((*t0[0] - *t0[2]).norm(), 0.0, kTol);
}

}  // namespace
}  // namespace meltlab::render
