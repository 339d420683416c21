#pragma once
// Scene description of the ice/liquid ray tracer: camera, lights, the ice material of Eq.
// 6.11 (or a physically based reference), the ground with the liquid of Eq. 7.17, the
// environment and the outputs. Inert data; read from YAML by parse_render_scene (unknown keys
// are errors naming the file, line and key). Every value not given in chapter 6 is a named
// parameter here (spec §12, "Ice material" and "Liquid") and is written to the run log by
// describe_render_scene.
//
// Units: mesh units and the world frame of camera.h (z up, ground plane z = ground.z).
// Colours are linear RGB.

#include <meltlab/render/camera.h>
#include <meltlab/render/fog/scene_fog.h>
#include <meltlab/render/material/optics.h>
#include <meltlab/render/texture/assets.h>
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

using Rgb = Eigen::Vector3d;

struct DirectionalLight {
  Vec3d to_light = Vec3d(0.4, -0.3, 0.85);  ///< direction towards the light (normalised on use)
  Rgb colour = Rgb(1, 1, 1);                ///< Izr: multiplies ca, cd and cs
};

enum class IceModel {
  kMonograph,  ///< Eq. 6.11: one front-face refraction, environment lookups
  kPhysical,   ///< reference: refract in and out (internal reflections), Beer absorption, traced
};
enum class SpecularTerm {
  kRsV,  ///< (Rs·V)^n as in Eq. 6.4 and 7.1 (default; Rs = L reflected about N)
  kRsL,  ///< (Rs·L)^n as printed in Eq. 6.11 (`specular_term_6_11`)
};

struct IceMaterial {
  IceModel model = IceModel::kMonograph;
  double ca = 0.08, cd = 0.25, cs = 0.6, n_spec = 60;  ///< ambient, diffuse, specular, exponent
  double cr = 1.0;                                     ///< environment reflection share (× F)
  double ct = 1.0;                                     ///< transmission share (× (1 - F))
  FresnelMode fresnel = FresnelMode::kFull;            ///< `fresnel_mode`
  SpecularTerm specular = SpecularTerm::kRsV;
  bool dispersion = true;                      ///< three refraction directions (Eq. 6.8)
  double eta = kIceEta;                        ///< used when dispersion is off
  std::array<double, 3> eta_rgb = kIceEtaRgb;  ///< ice indices per channel
  double texture_scale = 0.0;                  ///< milky-ice feature size, mesh units; 0 = 5 % of the object's size
  /// Non-empty: tdiff from this image instead of the milky ice, projected along the dominant
  /// axis of the geometric normal (as the normal map) with period `texture_tile`.
  std::filesystem::path texture_file;
  double texture_tile = 0.0;     ///< ice texture image period, mesh units; 0 = 20 % of the object's size
  bool normal_map = false;       ///< Eq. 6.12 (replaces the normal; triplanar, see integrator/ice_surface.h)
  double normal_map_tile = 0.0;  ///< normal-map period, mesh units; 0 = 20 % of the object's size
  double normal_map_bump = 1.0;
  std::filesystem::path normal_map_file;  ///< non-empty: the normal map (rgb = N/2 + ½) read from this image
  /// Physical model: Beer absorption per mesh unit, per channel (clear ice absorbs red most).
  std::array<double, 3> absorption{0.6, 0.25, 0.15};
  int max_internal_bounces = 6;  ///< physical model: internal reflections followed
};

struct GroundMaterial {
  std::optional<double> z;  ///< ground plane height, mesh units (`ground_z`); unset = the mesh's lowest point
  double tile = 0.0;        ///< ground texture period, mesh units; 0 = 50 % of the object's size
  double ca = 0.25, cd = 0.75, cs = 0.3, n_spec = 30;  ///< Phong (Eq. 2.13) of the substrate
  bool textured = true;                                ///< false: tdiff = 1 (a plain substrate)
  std::filesystem::path texture_file;                  ///< non-empty: the diffuse texture tdiff read from this image
  // Liquid (Eq. 7.14-7.17); monograph values.
  double a = 0.6;                     ///< wet darkening exponent factor
  double cr = 0.2;                    ///< water environment reflection
  double tilt_s = 0.7, tilt_t = 0.7;  ///< rim normal tilt (Eq. 7.3's cs, ct)
  double d = 0.1;                     ///< film refraction offset, in texture periods (Eq. 7.5)
  bool rs_uses_n_star = true;         ///< `Rs_uses_N_star`: specular with N* as the text says
  bool liquid = true;                 ///< shade the liquid mask when one is given
};

struct RenderOutputs {
  bool exr = true, png = true;
  double exposure = 1.0, gamma = 2.2;  ///< PNG display transform
};

/// How the renderer looks its image assets up (environment, ground texture, normal map).
enum class TextureFilter {
  kBilinear,  ///< point-sampled bilinear at the finest level (the monograph's GPU lookups)
  kMipmap,    ///< OpenImageIO's TextureSystem: MIP-mapped, anisotropic, footprints from ray differentials
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
