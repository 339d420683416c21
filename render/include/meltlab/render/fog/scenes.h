#pragma once
// The procedural scenes of seed 002's spec §4 (the thesis's assets are unavailable), in the
// harness's world frame (z up, metres): the spec's y-up coordinates (x, y, z) become (x, -z, y).
//
//   S1 "sphere": a unit sphere at the origin above the plane z = -1; a spotlight at (-2, 0, 2)
//      aimed at the origin, half-angle 30°; camera at (0, -5, 0.5) looking at the origin, vertical
//      field of view 45°; k_d = 0.7, k_s = 0.3, n = 20.
//   S2 "street": the ground z = 0 and `lights` spotlights at height 5 m along x every 10 m,
//      pointing down, half-angle 40°; the camera at 1.7 m height looking along the row.
//   S3 "lamp": one lamp (a spotlight pointing down, half-angle 35°, 4 m up) or the same lamp as
//      an isotropic point light (Fig. 5.4), a post, the ground.
//   S4 "random rays": random eye/light/cone configurations with the eye inside the cone, the light
//      behind the eye, h -> 0 (down to 1e-3 l, above fsa.h_min) and m -> ∞.
// Geometry is analytic (spheres, planes, boxes-as-planes are not needed): the G-buffer of
// fog/fog_frame.h traces it exactly; the same scenes as meshes go through Embree there.

#include <meltlab/render/camera.h>
#include <meltlab/render/fog/airlight.h>

#include <cstdint>
#include <string>
#include <vector>

namespace meltlab::render::fog {

struct AnalyticSphere {
  Vec3 centre = Vec3::Zero();
  double radius = 1;
};
/// The plane n·x = offset, seen from the side n points to.
struct AnalyticPlane {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0;
};
/// A vertical cylinder (a lamp post): axis along z through (x, y), from z0 to z1.
struct AnalyticPost {
  double x = 0, y = 0, radius = 0.08, z0 = 0, z1 = 4;
};

struct FogScene {
  std::string name;
  Pinhole camera;
  double far_m = 200;  ///< view rays end here when they hit nothing (a camera far plane for all methods)
  std::vector<Spotlight> lights;
  FogMedium medium;
  FogMaterial material;
  std::vector<AnalyticSphere> spheres;
  std::vector<AnalyticPlane> planes;
  std::vector<AnalyticPost> posts;
};

/// S1 at `width` × `height` (4:3), extinction kt.
FogScene scene_sphere(double kt, int width, int height);
/// S2 with `lights` lamps (4 in the spec; 1-16 for the cost study).
FogScene scene_street(double kt, int width, int height, int lights = 4);
/// S3: the lamp as a spotlight or (point = true) as an isotropic point light.
FogScene scene_lamp(double kt, int width, int height, bool point);

/// One S4 configuration: the eye at `origin`, a view ray, one light, a medium.
struct RayConfig {
  Vec3 origin = Vec3::Zero(), dir = Vec3::UnitX();
  double m = 1;
  Spotlight light;
  FogMedium medium;
  std::string kind;  ///< "random", "eye_inside", "light_behind", "near_light", "to_infinity"
};

/// `count` S4 configurations from `seed` (deterministic): a fifth each of the special kinds.
std::vector<RayConfig> random_ray_configs(int count, std::uint64_t seed);

}  // namespace meltlab::render::fog
