#pragma once
// The ice materials of the ray tracer (integrator/ice_surface.h), their parameters and which
// of their terms a frame computes.
//
// Monograph ice (Eq. 6.11), at the first hit with V the unit vector to the eye and N the smooth
// (or normal-mapped) outward normal facing V:
//   I = (ca + Σ_lights Izr·cd·max(0, N·L))·tdiff + Σ_lights Izr·cs·max(0, Rs·V)^n
//       + cr·F·tenv(Re) + ct·(1 - F)·tenv(T)
//   Re = 2N(N·V) - V (Eq. 6.3); Rs = L reflected about N; T = refract(-V, N, 1/η) (Eq. 6.7),
//   per channel with η_R, η_G, η_B when dispersion is on (Eq. 6.8); F from Eq. 6.9 or 6.10 at
//   cos Θi = N·V, air → ice (1 → η_G, or η without dispersion). The ambient ca is white and
//   added once; Izr is each light's colour; `specular: RsL` uses the printed (Rs·L)^n. tdiff =
//   milky_ice(p) (solid procedural texture), or the image `ice.texture_file` projected along
//   the dominant axis of the geometric normal with period `ice.texture_tile`. The refracted ray
//   is NOT traced: as in the monograph it only looks the environment up (one refraction at
//   front faces).
// Normal map (Eq. 6.12), both models: N = 2(rgb - ½) in a tangent frame; the map is projected
// along the dominant axis of the geometric normal (triplanar, `normal_map_space` = tangent,
// projected per axis), and its N replaces the surface normal for reflection, refraction and
// lighting.
// Physical ice (a reference): at the entry, reflection F·(traced reflected ray) and
// transmission (1 - F) per channel (η per channel if dispersion, else η): the ray is refracted
// in, traced to the exit through the ice, attenuated by exp(-σ_c·d) (Beer), refracted out with
// the exit Fresnel weight (the internally reflected part followed up to max_internal_bounces,
// or until its weight is below 1e-4), and the outgoing ray is traced against the scene
// (IceSurroundings::radiance_outside). No ambient/diffuse/Phong terms: the sun of the
// environment map gives the highlights.
// Footprints (texture_filter: mipmap): the reflected and refracted rays carry the footprint of
// the hit through the change of the interpolated normal (material/optics.h's
// reflect_differential / refract_differential; the normal map's own slope change is not
// followed); the physical model's paths through the ice look up the finest level. The
// milky-ice texture is solid and procedural (not filtered).

#include <meltlab/render/material/optics.h>
#include <meltlab/render/material/shading.h>
#include <meltlab/render/texture/lookup.h>

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace meltlab::render {

enum class IceModel {
  kMonograph,  ///< Eq. 6.11: one front-face refraction, environment lookups
  kPhysical,   ///< reference: refract in and out (internal reflections), Beer absorption, traced
};
enum class SpecularTerm {
  kRsV,  ///< (Rs·V)^n as in Eq. 6.4 and 7.1 (default; Rs = L reflected about N)
  kRsL,  ///< (Rs·L)^n as printed in Eq. 6.11 (`specular_term_6_11`)
};

/// The ice parameters of the render scene (render_scene.h reads them).
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
  bool normal_map = false;       ///< Eq. 6.12 (replaces the normal; triplanar, see above)
  double normal_map_tile = 0.0;  ///< normal-map period, mesh units; 0 = 20 % of the object's size
  double normal_map_bump = 1.0;
  std::filesystem::path normal_map_file;  ///< non-empty: the normal map (rgb = N/2 + ½) read from this image
  /// Physical model: Beer absorption per mesh unit, per channel (clear ice absorbs red most).
  std::array<double, 3> absorption{0.6, 0.25, 0.15};
  int max_internal_bounces = 6;  ///< physical model: internal reflections followed
};

/// Which terms of the ice a frame computes (design.md, "skip what a scene does not need").
struct IcePlan {
  bool ice_texture = true, ice_specular = true, ice_reflection = true, ice_transmission = true;
  bool fresnel = true, dispersion = true, normal_map = false;
};
/// The monograph model skips the terms with a zero weight (no texture if ca = cd = 0, no
/// specular if cs = 0 or there is no light, no environment reflection if cr = 0, no refraction
/// or dispersion if ct = 0, no Fresnel if both); the physical model computes reflection and
/// transmission only. Dispersion off or equal indices: one refraction. What is skipped is
/// appended to `skipped` (human-readable).
IcePlan plan_ice(const IceMaterial& material, bool lit, std::vector<std::string>& skipped);

/// The textures an ice material looks up.
struct IceTextures {
  const EnvironmentTexture* environment = nullptr;  ///< tenv
  const ImageTexture* normal_map = nullptr;         ///< Eq. 6.12; needed if the plan has normal_map
  const ImageTexture* image = nullptr;              ///< tdiff from an image; nullptr: the milky ice
};

/// An ice material: the radiance leaving a hit towards the eye.
class IceShader {
 public:
  virtual ~IceShader() = default;
  /// `d`: the unit direction of the ray that hit; `rd`: its footprint at the hit (o: of the
  /// point, d: of the direction) or nullptr.
  virtual Rgb shade(const SurfaceHit& hit, const Eigen::Vector3d& d, const RayDifferential* rd) const = 0;

 protected:
  /// The material and the textures must outlive the shader.
  IceShader(const IceMaterial& material, const IcePlan& plan, const IceTextures& textures);
  /// The shading normal facing V (normal-mapped if planned); with a footprint `dp` of the
  /// point also its change dN (of the interpolated normal) and the map's filtered lookup.
  Eigen::Vector3d facing_normal(const SurfaceHit& hit, const Eigen::Vector3d& V, const Differential* dp,
                                Differential* dN) const;

  const IceMaterial& material_;
  IcePlan plan_;
  IceTextures textures_;
};

/// Eq. 6.11 (above).
class MonographIce final : public IceShader {
 public:
  MonographIce(const IceMaterial& material, const IcePlan& plan, const IceTextures& textures,
               const std::vector<Light>& lights);
  Rgb shade(const SurfaceHit& hit, const Eigen::Vector3d& d, const RayDifferential* rd) const override;

 private:
  Rgb tdiff(const SurfaceHit& hit, const Differential* dp) const;  ///< milky ice or the projected image

  const std::vector<Light>& lights_;
};

/// The physical reference (above). `offset`: how far secondary rays start off the surface
/// (mesh units), and the t_min of the crossings asked of `surroundings`.
class PhysicalIce final : public IceShader {
 public:
  PhysicalIce(const IceMaterial& material, const IcePlan& plan, const IceTextures& textures,
              const IceSurroundings& surroundings, double offset);
  Rgb shade(const SurfaceHit& hit, const Eigen::Vector3d& d, const RayDifferential* rd) const override;

 private:
  const IceSurroundings& surroundings_;
  double offset_;
};

}  // namespace meltlab::render
