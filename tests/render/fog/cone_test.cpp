// The lit part of a view ray (render/fog/cone.h) against the indicator crossings R-air finds by
// bisection (spec §6 target 5), and the listing's special-case logic beside it.

#include <meltlab/render/fog/cone.h>
#include <meltlab/render/fog/reference.h>
#include <meltlab/render/fog/scenes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace meltlab::render::fog {
namespace {

constexpr double kDeg = std::numbers::pi / 180;
// Spec §6.5: segment_in_cone agrees with the indicator crossings to 1e-9 m (relative to the
// distance for crossings far away: double rounding of a 60 m distance is ~1e-14 relative).
constexpr double kCrossingTol = 1e-9;

Cone cone_of(const RayConfig& c) {
  Cone k;
  k.apex = c.light.position - c.origin;
  k.axis = c.light.axis.normalized();
  k.cos_half = std::cos(c.light.profile.front().half_angle_rad);
  return k;
}

TEST(ConeSegment, HandBuiltCases) {
  Cone k;  // apex 5 m above, pointing down, 45°: the lit disc on z = -5... the eye at the origin
  k.apex = Vec3(0, 0, 5);
  k.axis = Vec3(0, 0, -1);
  k.cos_half = std::cos(45 * kDeg);
  // The eye is inside (straight below the apex); a horizontal ray leaves the cone at s = 5.
  ConeSegments s = segment_in_cone(Vec3::UnitX(), 100, k);
  ASSERT_EQ(s.count, 1);
  EXPECT_DOUBLE_EQ(s.parts[0].a, 0.0);
  EXPECT_NEAR(s.parts[0].b, 5.0, 1e-12);
  // Looking up the axis: lit up to the apex, then the backward nappe is dark. The line through
  // the apex is a double root: its position is conditioned as sqrt(ε) (1e-8 relative).
  s = segment_in_cone(Vec3::UnitZ(), 100, k);
  ASSERT_EQ(s.count, 1);
  EXPECT_NEAR(s.parts[0].b, 5.0, 5e-7);
  // A ray ending before it leaves: [0, m].
  s = segment_in_cone(Vec3::UnitX(), 3, k);
  ASSERT_EQ(s.count, 1);
  EXPECT_DOUBLE_EQ(s.parts[0].b, 3.0);
  // A ray from outside crossing the cone: origin shifted so the eye is at (-10, 0, 0).
  k.apex = Vec3(10, 0, 5);
  s = segment_in_cone(Vec3::UnitX(), 100, k);
  ASSERT_EQ(s.count, 1);
  EXPECT_NEAR(s.parts[0].a, 5.0, 1e-12);
  EXPECT_NEAR(s.parts[0].b, 15.0, 1e-12);
  // Parallel to a generator (c2 = 0, the linear case): V = (1, 0, -1)/√2 with the apex at
  // (1, 0, 0) enters at s = 1/√2 and never leaves. The listing divides by c2 = 0 here.
  k.apex = Vec3(1, 0, 0);
  const Vec3 along(1 / std::sqrt(2.0), 0, -1 / std::sqrt(2.0));
  s = segment_in_cone(along, std::numeric_limits<double>::infinity(), k);
  ASSERT_EQ(s.count, 1);
  EXPECT_NEAR(s.parts[0].a, 1 / std::sqrt(2.0), 1e-12);
  EXPECT_TRUE(std::isinf(s.parts[0].b));
  s = segment_in_cone(along, 10.0, k);
  ASSERT_EQ(s.count, 1);
  EXPECT_NEAR(s.parts[0].a, 1 / std::sqrt(2.0), 1e-12);
  EXPECT_EQ(s.parts[0].b, 10.0);
  const Interval src_linear = segment_in_cone_source(along, 10.0, k);
  EXPECT_FALSE(std::abs(src_linear.a - 1 / std::sqrt(2.0)) < 1e-6 && src_linear.b == 10.0)
      << "the listing got the linear case right after all: [" << src_linear.a << ", " << src_linear.b << "]";
  // The listing finds nothing when the discriminant is negative, also with the eye inside.
  k.apex = Vec3(0, 0, 5);
  k.cos_half = std::cos(60 * kDeg);
  EXPECT_EQ(segment_in_cone(Vec3(0, 0, -1), 10, k).hull().b, 10.0);
  const Interval src = segment_in_cone_source(Vec3(0, 0, -1), 10, k);
  EXPECT_EQ(src.b - src.a, 10.0) << "straight down the axis: both roots behind, the listing agrees here";
}

TEST(ConeSegment, AgreesWithTheIndicatorCrossingsOnS4) {
  const auto configs = random_ray_configs(100000, 2024);
  int differs_from_source = 0, eye_inside = 0, nonempty = 0;
  for (const RayConfig& c : configs) {
    const Cone k = cone_of(c);
    const ConeSegments seg = segment_in_cone(c.dir, c.m, k);
    const auto crossings = indicator_crossings(c.origin, c.dir, c.m, c.light.position, c.light.axis,
                                               c.light.profile.front().half_angle_rad);
    // The segment's finite interior ends are exactly the crossings.
    std::vector<double> ends;
    for (int i = 0; i < seg.count; ++i) {
      const Interval& p = seg.parts[static_cast<std::size_t>(i)];
      if (p.a > 0) ends.push_back(p.a);
      if (p.b < c.m) ends.push_back(p.b);
    }
    ASSERT_EQ(ends.size(), crossings.size()) << c.kind;
    for (std::size_t i = 0; i < ends.size(); ++i)
      ASSERT_NEAR(ends[i], crossings[i], kCrossingTol * std::max(1.0, crossings[i])) << c.kind;
    // The lit/unlit status of the eye agrees with the segment's start.
    const bool inside_eye = inside_cone(k, Vec3::Zero());
    eye_inside += inside_eye;
    if (inside_eye && c.m > 0) {
      ASSERT_TRUE(seg.count > 0 && seg.parts[0].a == 0) << c.kind;
    }
    nonempty += seg.count > 0;
    const Interval src = segment_in_cone_source(c.dir, c.m, k);
    const Interval robust = seg.hull();
    const double scale = std::max(1.0, std::isfinite(c.m) ? c.m : 1.0);
    auto same = [&](double x, double y) { return (std::isinf(x) && x == y) || std::abs(x - y) <= 1e-6 * scale; };
    if (!(same(src.a, robust.a) && same(src.b, robust.b)) && !(src.b <= src.a && seg.empty())) ++differs_from_source;
  }
  EXPECT_GT(eye_inside, 20000) << "S4 must exercise the eye inside the cone";
  EXPECT_GT(nonempty, 50000);
  // For rays in general position the listing's three special cases pick the right nappe: a lit
  // surface point or the eye inside the cone always gives a non-negative discriminant. It fails
  // only in degenerate cases (c2 = 0 above), which random rays do not hit.
  EXPECT_LT(differs_from_source, 10);
  std::printf("S4: %d of %zu rays where the listing's segment differs; eye inside the cone: %d\n", differs_from_source,
              configs.size(), eye_inside);
}

}  // namespace
}  // namespace meltlab::render::fog
