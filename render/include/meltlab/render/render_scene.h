#pragma once
// Scene description of the ice/liquid ray tracer: camera, lights, the ice material of Eq.
// 6.11 (or a physically based reference; material/ice.h), the ground with the liquid of Eq.
// 7.17 (material/ground.h), the texture filter (texture/lookup.h), the environment and the
// outputs. Inert data; read from YAML by parse_render_scene (unknown keys are errors naming
// the file, line and key). Every value not given in chapter 6 is a named parameter (spec §12,
// "Ice material" and "Liquid"); `meltlab render` writes the resolved scene into render.json
// (experiments/render_json.h).
//
// Units: mesh units and the world frame of camera.h (z up, ground plane z = ground.z).
// Colours are linear RGB.

#include <meltlab/render/camera.h>
#include <meltlab/render/fog/scene_fog.h>
#include <meltlab/render/material/ground.h>
#include <meltlab/render/material/ice.h>
#include <meltlab/render/texture/assets.h>
#include <meltlab/render/texture/lookup.h>
#include <meltlab/sim/mesh.h>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace meltlab::render {

struct DirectionalLight {
  Vec3d to_light = Vec3d(0.4, -0.3, 0.85);  ///< direction towards the light (normalised on use)
  Rgb colour = Rgb(1, 1, 1);                ///< Izr: multiplies ca, cd and cs
};

struct RenderOutputs {
  bool exr = true, png = true;
  double exposure = 1.0, gamma = 2.2;  ///< PNG display transform
};

struct RenderScene {
  std::optional<Camera> camera;                             ///< unset: framed automatically on the mesh (auto_camera)
  int width = 640, height = 480;                            ///< for the automatic camera
  TextureFilter texture_filter = TextureFilter::kBilinear;  ///< `texture_filter: bilinear|mipmap`
  std::vector<DirectionalLight> lights{DirectionalLight{}};
  IceMaterial ice;
  GroundMaterial ground;
  EnvironmentOptions environment;
  RenderOutputs outputs;
  /// Seed 002's spotlights in homogeneous fog (fog/scene_fog.h); unset: no fog.
  std::optional<fog::SceneFog> fog;
};

/// Reads a scene (all keys optional; defaults above). Top-level keys: camera (camera.h's
/// format), width, height, texture_filter, lights [{to_light, colour}], ice {...}, ground {...},
/// environment {width, height, to_sun, sun_radiance, file, layout}, outputs {exr, png, exposure, gamma},
/// fog {kt, albedo, far, spotlights [...], table {...}, ...} (fog/scene_fog.h).
/// Enumerations: ice.model monograph|physical, ice.fresnel full|schlick, ice.specular RsV|RsL.
/// Throws InputError naming `source`, the line and the key.
RenderScene parse_render_scene(const YAML::Node& node, const std::string& source);
RenderScene load_render_scene(const std::string& yaml_file);

/// A pinhole camera looking at the mesh's bounding box from the front-above (30° elevation,
/// from -y), with the whole box in view.
Pinhole auto_camera(const Vec3d& lower, const Vec3d& upper, int width, int height);

}  // namespace meltlab::render
