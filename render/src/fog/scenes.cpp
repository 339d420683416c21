// The procedural scenes S1-S4 of seed 002's spec §4 (fog/scenes.h).

#include <meltlab/render/fog/scenes.h>

#include <cmath>
#include <numbers>
#include <random>

namespace meltlab::render::fog {

namespace {

constexpr double kDeg = std::numbers::pi / 180;

Pinhole camera_fov(int width, int height, double fov_deg, const Vec3& eye, const Vec3& target) {
  const double fy = 0.5 * height / std::tan(0.5 * fov_deg * kDeg);
  return Pinhole::look_at(width, height, fy, eye, target, Vec3::UnitZ());
}

Spotlight spot(const Vec3& position, const Vec3& target, double half_angle_deg, double intensity) {
  Spotlight s;
  s.position = position;
  s.axis = (target - position).normalized();
  s.profile = {ConeStep{half_angle_deg * kDeg, 1.0}};
  s.intensity = intensity;
  return s;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0, 1);
  Vec3 v;
  do v = Vec3(n(rng), n(rng), n(rng));
  while (v.norm() < 1e-8);
  return v.normalized();
}

// `v` turned by `angle` towards a random perpendicular direction.
Vec3 perturb(const Vec3& v, double angle, std::mt19937_64& rng) {
  Vec3 p = random_unit(rng);
  p = (p - v * v.dot(p)).normalized();
  return (std::cos(angle) * v + std::sin(angle) * p).normalized();
}

}  // namespace

FogScene scene_sphere(double kt, int width, int height) {
  FogScene s;
  s.name = "S1_sphere";
  s.camera = camera_fov(width, height, 45, Vec3(0, -5, 0.5), Vec3::Zero());
  s.far_m = 100;
  s.lights = {spot(Vec3(-2, 0, 2), Vec3::Zero(), 30, 10.0)};
  s.medium.kt = kt;
  s.material = FogMaterial{0.7, 0.3, 20, Rgb(1, 1, 1)};
  s.spheres = {AnalyticSphere{Vec3::Zero(), 1.0}};
  s.planes = {AnalyticPlane{Vec3::UnitZ(), -1.0}};
  return s;
}

FogScene scene_street(double kt, int width, int height, int lights) {
  FogScene s;
  s.name = "S2_street";
  s.camera = camera_fov(width, height, 50, Vec3(-12, -3, 1.7), Vec3(30, 1, 2.0));
  s.far_m = 200;
  for (int k = 0; k < lights; ++k) {
    const Vec3 p(10.0 * k, 2.0, 5.0);
    s.lights.push_back(spot(p, p - Vec3::UnitZ(), 40, 60.0));
  }
  s.medium.kt = kt;
  s.material = FogMaterial{0.6, 0.2, 20, Rgb(0.8, 0.8, 0.75)};
  s.planes = {AnalyticPlane{Vec3::UnitZ(), 0.0}};
  for (int k = 0; k < lights; ++k) s.posts.push_back(AnalyticPost{10.0 * k, 2.4, 0.08, 0.0, 5.1});
  return s;
}

FogScene scene_lamp(double kt, int width, int height, bool point) {
  FogScene s;
  s.name = point ? "S3_lamp_point" : "S3_lamp_spot";
  s.camera = camera_fov(width, height, 50, Vec3(0, -9, 1.7), Vec3(0, 0, 2.5));
  s.far_m = 100;
  Spotlight l = spot(Vec3(0, 0, 4), Vec3(0, 0, 0), 35, 30.0);
  if (point) l.kind = LightKind::kPoint;
  s.lights = {l};
  s.medium.kt = kt;
  s.material = FogMaterial{0.6, 0.3, 20, Rgb(0.85, 0.8, 0.7)};
  s.planes = {AnalyticPlane{Vec3::UnitZ(), 0.0}};
  s.posts = {AnalyticPost{0.0, 0.35, 0.08, 0.0, 4.2}};
  return s;
}

std::vector<RayConfig> random_ray_configs(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  const double kts[] = {0.01, 0.04, 0.1, 0.3, 1.0};
  const char* kinds[] = {"random", "eye_inside", "light_behind", "near_light", "to_infinity"};
  std::vector<RayConfig> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    RayConfig c;
    c.kind = kinds[i % 5];
    c.medium.kt = kts[static_cast<std::size_t>(rng() % 5)];
    const double dist = 0.5 * std::pow(40.0, unit(rng));  // 0.5 .. 20 m, log-uniform
    const Vec3 S = dist * random_unit(rng);
    const double half = (5 + 75 * unit(rng)) * kDeg;
    c.light.position = c.origin + S;
    c.light.profile = {ConeStep{half, 1.0}};
    c.light.intensity = 1.0;
    c.dir = random_unit(rng);
    c.m = 0.1 + 60 * unit(rng);
    // The axis points at a random point of the ray, turned by up to twice the half-angle, so that
    // most rays cross the cone.
    const Vec3 aim = c.origin + (0.2 + 20 * unit(rng)) * c.dir;
    Vec3 axis = perturb((aim - c.light.position).normalized(), 2 * half * unit(rng), rng);
    if (c.kind == std::string("eye_inside")) {
      axis = perturb((c.origin - c.light.position).normalized(), 0.9 * half * unit(rng), rng);
    } else if (c.kind == std::string("light_behind")) {
      if (S.dot(c.dir) > 0) c.dir = -c.dir;
      axis = perturb((c.origin + 5 * unit(rng) * c.dir - c.light.position).normalized(), 1.5 * half * unit(rng), rng);
    } else if (c.kind == std::string("near_light")) {
      c.dir = perturb(S.normalized(), 1e-3 * std::pow(10.0, unit(rng)), rng);  // h/l in [1e-3, 1e-2]
      if (unit(rng) < 0.5) c.m = dist * (0.5 + unit(rng));                     // ends before or after the light
    } else if (c.kind == std::string("to_infinity")) {
      c.m = std::numeric_limits<double>::infinity();
    }
    c.light.axis = axis;
    out.push_back(c);
  }
  return out;
}

}  // namespace meltlab::render::fog
