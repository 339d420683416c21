// The airlight of seed 002 (render/fog/airlight.h) against R-air and its limits (spec §6.2-6.4,
// 6.6, 6.8).

#include <meltlab/render/fog/airlight.h>
#include <meltlab/render/fog/airlight_f.h>
#include <meltlab/render/fog/reference.h>
#include <meltlab/render/fog/scenes.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace meltlab::render::fog {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;
// The analytic airlight with the accurate F against R-air. The spec accepts R-air when its two
// rules agree to 1e-8; rays within 1e-3 l of the light (a foot-point peak 1e3 times narrower
// than the ray) differ by up to 1.1e-8 here. 5e-8 checks derivation, segment and F together.
constexpr double kExactVsRair = 5e-8;

Spotlight test_light() {
  Spotlight s;
  s.position = Vec3(3, 4, 2);
  s.axis = Vec3(-0.3, -0.6, -1).normalized();
  s.profile = {ConeStep{35 * kDeg, 1.0}};
  return s;
}

TEST(Airlight, ExactEqualsRairOnS4) {
  const auto configs = random_ray_configs(3000, 99);
  int rejected = 0, compared = 0;
  for (const RayConfig& c : configs) {
    const RairResult ref = r_air(c.origin, c.dir, c.m, c.light, c.medium);
    if (!ref.accepted) {
      ++rejected;
      continue;
    }
    const double exact = airlight_unit(c.origin, c.dir, c.m, c.light, c.medium, FogFunctions{}, FogModelOptions{});
    ASSERT_NEAR(exact, ref.value, kExactVsRair * ref.value + 1e-300)
        << c.kind << " kt " << c.medium.kt << " m " << c.m << " S " << (c.light.position - c.origin).transpose()
        << " V " << c.dir.transpose() << " confirm " << ref.confirm << " knots " << ref.knots.size();
    ++compared;
  }
  EXPECT_LT(rejected, 30) << "R-air's two rules disagreed on more than 1 % of the rays";
  EXPECT_GT(compared, 2900);
}

TEST(Airlight, ThinMediumLimit) {
  // k_t -> 0: L_a/k_t -> I/(4π h) [atan((b - t)/h) - atan((a - t)/h)] (Ω = 1).
  Spotlight light = test_light();
  light.kind = LightKind::kPoint;
  const Vec3 V = Vec3(1, 1, 0.2).normalized();
  const double m = 12;
  const RayLight g = ray_light(V, light.position, 1e-4);
  const double limit = (std::atan((m - g.t) / g.h) - std::atan(-g.t / g.h)) / (4 * kPi * g.h);
  double prev_err = 1;
  for (double kt : {1e-2, 1e-4, 1e-6}) {
    FogMedium med;
    med.kt = kt;
    const double la = airlight_unit(Vec3::Zero(), V, m, light, med, FogFunctions{}, FogModelOptions{});
    const double err = std::abs(la / kt - limit) / limit;
    EXPECT_LT(err, prev_err) << "kt " << kt;
    prev_err = err;
  }
  EXPECT_LT(prev_err, 1e-4) << "O(k_t·(l + m)) at k_t = 1e-6";
}

TEST(Airlight, EmptyIntervalAndAdditivity) {
  const RayLight g = ray_light(Vec3(0, 1, 0), Vec3(1, 5, 1), 1e-4);
  FogMedium med;
  med.kt = 0.1;
  EXPECT_EQ(airlight_interval(g, med, 3.0, 3.0, FogFunctions{}), 0.0);
  for (auto [a, b, c] : {std::tuple{0.0, 2.0, 9.0}, std::tuple{4.0, 5.0, 6.0}, std::tuple{1.0, 20.0, 1e9}}) {
    const double ab = airlight_interval(g, med, a, b, FogFunctions{});
    const double bc = airlight_interval(g, med, b, c, FogFunctions{});
    const double ac = airlight_interval(g, med, a, c, FogFunctions{});
    EXPECT_NEAR(ab + bc, ac, 1e-12 * ac);
  }
  // The same with the table: additivity is exact for any F (a telescoping difference).
  TableOptions o;
  o.n = 32;
  const FogTable f = f_table(o);
  const FogFunctions fn{&f, nullptr, nullptr};
  EXPECT_NEAR(airlight_interval(g, med, 0, 2, fn) + airlight_interval(g, med, 2, 9, fn),
              airlight_interval(g, med, 0, 9, fn), 1e-12);
}

TEST(Airlight, ReducesToSunEtAlsPointLight) {
  // A cone of half-angle π lights everything: the segment is [0, m] and the result equals Sun et
  // al.'s A0 [F(A1, v_m) - F(A1, φ/2)] to rounding (φ/2 from acos against π/4 + ½ atan(-t/h)).
  constexpr double kMachine = 1e-12;
  TableOptions o;
  const FogTable f = f_table(o);
  for (const FogFunctions& fn : {FogFunctions{}, FogFunctions{&f, nullptr, nullptr}})
    for (const RayConfig& c : random_ray_configs(500, 5)) {
      if (!std::isfinite(c.m)) continue;
      Spotlight wide = c.light;
      wide.profile = {ConeStep{kPi, 1.0}};
      const double spot = airlight_unit(c.origin, c.dir, c.m, wide, c.medium, fn, FogModelOptions{});
      const double sun = airlight_point_sun(c.origin, c.dir, c.m, c.light.position, c.medium, fn);
      Spotlight point = c.light;
      point.kind = LightKind::kPoint;
      const double pt = airlight_unit(c.origin, c.dir, c.m, point, c.medium, fn, FogModelOptions{});
      // Relative to the prefactor A0 (the F values are O(1)): the two paths round differently.
      const RayLight g = ray_light(c.dir, c.light.position - c.origin, 1e-4);
      const double a0 = c.medium.kt * std::exp(-c.medium.kt * g.t) / (2 * kPi * g.h);
      ASSERT_NEAR(spot, sun, kMachine * (sun + a0)) << c.kind;
      ASSERT_EQ(spot, pt);
    }
}

TEST(PreparedLight, ItsIntensityIsTheRingsAndOnTheEdgesTheConesLitTest) {
  // Away from the rings' edges the intensity is that of the ring the angle from the axis falls
  // in (the angle overload); on the edges (points placed at each ring's angle ± 1 ulp-ish) it is
  // lit exactly where the airlight's cone test (inside_cone, with the same unit axis and
  // cosine) says so, so that the surface and the airlight agree there.
  Spotlight light = test_light();
  light.axis = Vec3(-0.3, -0.6, -1);  // not unit: it is normalised once
  light.profile = {ConeStep{10 * kDeg, 3.0}, ConeStep{20 * kDeg, 2.0}, ConeStep{30 * kDeg, 1.0}};
  const PreparedLight prepared(light);
  const Vec3 axis = light.axis.normalized(), side = axis.unitOrthogonal();
  int away = 0, edges = 0;
  for (const RayConfig& c : random_ray_configs(2000, 5)) {
    const Vec3 d = c.origin - light.position;
    const double theta = std::acos(std::clamp(axis.dot(d) / d.norm(), -1.0, 1.0));
    bool near_edge = false;
    for (const ConeStep& ring : light.profile) near_edge |= std::abs(theta - ring.half_angle_rad) < 1e-9;
    if (near_edge) continue;
    ASSERT_EQ(prepared.intensity_at(c.origin), light.intensity_at(theta)) << theta;
    ASSERT_EQ(light.intensity_at(c.origin), light.intensity_at(theta)) << theta;
    ++away;
  }
  for (std::size_t k = 0; k < light.profile.size(); ++k)
    for (double dist : {0.5, 3.0, 40.0})
      for (double eps : {-1e-15, 0.0, 1e-15}) {
        const double a = light.profile[k].half_angle_rad + eps;
        const Vec3 x = light.position + dist * (std::cos(a) * axis + std::sin(a) * side);
        Cone cone;
        cone.apex = light.position;
        cone.axis = axis;
        cone.cos_half = std::cos(light.profile[k].half_angle_rad);
        // Lit by ring k or an inner one exactly when inside ring k's cone.
        ASSERT_EQ(prepared.intensity_at(x) >= light.profile[k].intensity, inside_cone(cone, x)) << k << " " << a;
        ++edges;
      }
  EXPECT_GT(away, 1900);
  EXPECT_EQ(edges, 27);
  // The weights are the steps I_k - I_{k+1}.
  ASSERT_EQ(prepared.weight.size(), 3u);
  EXPECT_EQ(prepared.weight[0], 1.0);
  EXPECT_EQ(prepared.weight[1], 1.0);
  EXPECT_EQ(prepared.weight[2], 1.0);
}

TEST(Airlight, NestedConesAreLinearAndMatchRair) {
  // Three rings 10°/20°/30° with intensities 3, 2, 1: the sum of cone airlights weighted by the
  // steps, against R-air with the stepped indicator.
  Spotlight light = test_light();
  light.profile = {ConeStep{10 * kDeg, 3.0}, ConeStep{20 * kDeg, 2.0}, ConeStep{30 * kDeg, 1.0}};
  FogMedium med;
  med.kt = 0.08;
  int lit = 0;
  for (const RayConfig& c : random_ray_configs(2000, 11)) {
    Spotlight l = light;
    l.position = c.light.position;
    l.axis = c.light.axis;
    const RairResult ref = r_air(c.origin, c.dir, c.m, l, med);
    if (!ref.accepted) continue;
    const double a = airlight_unit(c.origin, c.dir, c.m, l, med, FogFunctions{}, FogModelOptions{});
    ASSERT_NEAR(a, ref.value, kExactVsRair * ref.value + 1e-300) << c.kind;
    lit += ref.value > 0;
    // Linear in I: doubling every ring doubles the airlight.
    Spotlight twice = l;
    for (ConeStep& s : twice.profile) s.intensity *= 2;
    ASSERT_NEAR(airlight_unit(c.origin, c.dir, c.m, twice, med, FogFunctions{}, FogModelOptions{}), 2 * a,
                1e-14 * a + 1e-300);
  }
  EXPECT_GT(lit, 500);
}

TEST(Airlight, PhysicalSanity) {
  const Spotlight light = test_light();
  const Vec3 V = Vec3(1, 1.2, 0.1).normalized();
  const double m = 30;
  // An interior maximum in k_t: 0 at k_t = 0, rising, falling towards 0.
  std::vector<double> curve;
  for (double kt : {0.0, 0.001, 0.01, 0.05, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0}) {
    FogMedium med;
    med.kt = kt;
    const double la = airlight_unit(Vec3::Zero(), V, m, light, med, FogFunctions{}, FogModelOptions{});
    EXPECT_GE(la, 0.0);
    // Never above the unattenuated integral k_t ∫ I/(4π d²) dx over the same segment.
    const RairResult no_att = [&] {
      FogMedium tiny;
      tiny.kt = 1e-12;
      return r_air(Vec3::Zero(), V, m, light, tiny);
    }();
    EXPECT_LE(la, kt / 1e-12 * no_att.value * (1 + 1e-8));
    curve.push_back(la);
  }
  EXPECT_EQ(curve.front(), 0.0);
  const auto peak = std::max_element(curve.begin(), curve.end()) - curve.begin();
  EXPECT_GT(peak, 0);
  EXPECT_LT(peak, static_cast<long>(curve.size()) - 1);
  EXPECT_LT(curve.back(), 1e-3 * curve[static_cast<std::size_t>(peak)]);
}

TEST(Airlight, TablesAtN64OnS4) {
  // E2 on the S4 rays (spec §6.4, the goal at N = 64: median < 0.5 %, max < 2 %) with
  // the floor of 1e-4 of the set's maximum, with the harness's table (H stored as K; u³ nodes,
  // v dense towards π/2 and interpolated in v: fog_tables.h). The measured values over N are in
  // `meltlab fog bench` (20 000 rays: median 0.019 %, max 0.33 %). On these 4000 rays: median
  // 1.5e-6, p99 0.058 %, max 0.18 %; guarded at 0.5 % (p99) and 1 % (max), 5x the measured
  // values and half the goal's 2 %.
  // (The √u table with uniform v missed the max: 5.8 % at rays within 1e-3 l of the light.)
  TableOptions o;
  o.n = 64;
  o.u_warp = AxisWarp::kCbrt;
  o.v_warp = AxisWarp::kSqrtHi;
  o.v_interp = InterpSpace::kValue;
  const FogTable f = f_table(o), h = h_table(o);
  FogFunctions fn{&f, nullptr, nullptr};
  fn.h = &h;
  const auto configs = random_ray_configs(4000, 3);
  std::vector<double> ref, fast;
  for (const RayConfig& c : configs) {
    ref.push_back(airlight_unit(c.origin, c.dir, c.m, c.light, c.medium, FogFunctions{}, FogModelOptions{}));
    fast.push_back(airlight_unit(c.origin, c.dir, c.m, c.light, c.medium, fn, FogModelOptions{}));
  }
  const double floor = 1e-4 * *std::max_element(ref.begin(), ref.end());
  std::vector<double> rel;
  for (std::size_t i = 0; i < ref.size(); ++i) rel.push_back(std::abs(fast[i] - ref[i]) / std::max(ref[i], floor));
  std::sort(rel.begin(), rel.end());
  std::printf("S4 E2 at N = 64: median %.3g, p99 %.3g, max %.3g\n", rel[rel.size() / 2], rel[rel.size() * 99 / 100],
              rel.back());
  EXPECT_LT(rel[rel.size() / 2], 0.005);
  EXPECT_LT(rel[rel.size() * 99 / 100], 0.005);
  EXPECT_LT(rel.back(), 0.01);
}

}  // namespace
}  // namespace meltlab::render::fog
