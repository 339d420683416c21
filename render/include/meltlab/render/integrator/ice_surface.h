#pragma once
// Ray tracer of melting ice on a wet ground (monograph chapters 6-7, spec §7-8), on the CPU:
// an Embree BVH over the current mesh (refitted or rebuilt each cycle), primary rays from a
// camera.h camera (one ray per pixel centre), image tiles of 16×16 pixels in parallel (TBB).
//
// Ice, monograph model (Eq. 6.11), at the first hit with V the unit vector to the eye and N
// the smooth (or normal-mapped) outward normal facing V:
//   I = (ca + Σ_lights Izr·cd·max(0, N·L))·tdiff + Σ_lights Izr·cs·max(0, Rs·V)^n
//       + cr·F·tenv(Re) + ct·(1 - F)·tenv(T)
//   Re = 2N(N·V) - V (Eq. 6.3); Rs = L reflected about N; T = refract(-V, N, 1/η) (Eq. 6.7),
//   per channel with η_R, η_G, η_B when dispersion is on (Eq. 6.8); F from Eq. 6.9 or 6.10 at
//   cos Θi = N·V, air → ice (1 → η_G, or η without dispersion). The ambient ca is white and added
//   once; Izr is each light's colour; `specular: RsL` uses the printed (Rs·L)^n. tdiff = milky_ice(p) (solid
//   procedural texture), or the image `ice.texture_file` projected along the dominant axis of
//   the geometric normal with period `ice.texture_tile`. The refracted ray is NOT traced: as in the monograph it only
//   looks the environment up (one refraction at front faces). Normal map (Eq. 6.12): N = 2(rgb - ½) in a tangent frame;
//   the map is projected along the dominant axis of the geometric normal (triplanar, `normal_map_space` = tangent,
//   projected per axis), and its N replaces the surface normal for reflection, refraction and lighting.
// Ice, physical reference: at the entry, reflection F·(traced reflected ray) and transmission
// (1 - F) per channel (η per channel if dispersion, else η): the ray is refracted in, traced
// to the exit through the ice, attenuated by exp(-σ_c·d) (Beer), refracted out with the
// exit Fresnel weight (internally reflected part followed up to max_internal_bounces, or
// until its weight is below 1e-4), and
// the outgoing ray is traced against the scene (ice again: its environment value — no
// further recursion; ground: shaded; else the environment). No ambient/diffuse/Phong terms:
// the sun of the environment map gives the highlights.
// Ground (plane z = ground.z, normal +z), Eq. 7.17 with w = step(p, mask) at the pixel's
// texel (bilinear mask and threshold, neighbours one texel away):
//   N* = normalize([tilt_s·(w_left - w_right), tilt_t·(w_down - w_up), 1])  (w_down at t-1)
//   t*diff = tdiff(s - d·Vx·w, t - d·Vy·w)      (s, t in ground-texture periods)
//   I = ((ca + Σ Izr·cd·max(0, N*·L))·t*diff + Σ Izr·cs·max(0, Rs·V)^n)^(1 + a·w) + cr·tenv(R*e)·w
//   (the base is clamped at 0 before the power; values above 1 — highlights — are not clamped)
//   Rs and R*e use N* (`rs_uses_n_star`). Without a mask (or with no texel at or above p,
//   or ground.liquid off) the ground is plain Phong (Eq. 2.13) × tdiff.
// No shadows and no ice seen through the ground, as in the monograph.
// Fog (scene `fog:`, seed 002): after a pixel is shaded, fog/scene_fog.h's FogShader attenuates
// it by e^{-k_t m} (m: the first surface, ice or ground, or the fog's `far`) and adds each
// spotlight's airlight and surface terms with the hit material's Phong coefficients.
//
// Texture lookups (scene `texture_filter`): `bilinear` (default) point-samples the environment,
// the ground texture and the normal map bilinearly at their finest level, as the monograph's GPU
// did; `mipmap` looks them up through OpenImageIO's TextureSystem (texture/filtered.h) with
// the pixel's footprint: ray differentials of the primary rays (the rays through the next pixel
// to the right and below), carried to the ground plane and to the ice's tangent plane, and
// through reflection and refraction with the change of the interpolated normal (material/optics.h's
// reflect_differential / refract_differential; pbrt's scheme). The physical model's paths
// through the ice look up the finest level. The milky-ice texture is solid and procedural
// (not filtered).
//
// Skip what the scene does not need (design.md): terms with a zero weight are not computed
// (no environment reflection if cr = 0, no refraction or dispersion lookups if ct = 0, no
// Fresnel if both, no specular if cs = 0, no texture if ca = cd = 0, no liquid when the mask
// is dry or absent, no rim normals if tilt = 0, no film offset if d = 0), dispersion off or
// equal indices use one refraction. plan() lists what is skipped; it is logged once per
// change of plan.

#include <meltlab/render/camera.h>
#include <meltlab/render/embree/mesh_bvh.h>
#include <meltlab/render/texture/assets.h>
#include <meltlab/render/render_scene.h>
#include <meltlab/sim/liquid_mask.h>

#include <memory>
#include <string>
#include <vector>

namespace meltlab::render {

class FilteredTextures;
namespace fog {
class FogShader;
}

/// Which terms a frame computes (from the scene's weights and the current mask).
struct ShadingPlan {
  bool ice_texture = true, ice_specular = true, ice_reflection = true, ice_transmission = true;
  bool fresnel = true, dispersion = true, normal_map = false;
  bool liquid = false, liquid_rim = false, liquid_offset = false, liquid_reflection = false, ground_specular = true;
  std::vector<std::string> skipped;  ///< human-readable list of what is not computed
};

struct FrameStats {
  BvhUpdate bvh = BvhUpdate::kNone;
  double bvh_ms = 0, trace_ms = 0;
  std::size_t triangles = 0;
};

class IceRenderer {
 public:
  explicit IceRenderer(RenderScene scene);
  ~IceRenderer();

  /// Loads the current mesh into the BVH (refit if only positions changed). The first call
  /// also resolves the size-relative defaults (texture scales, automatic camera).
  template <class Real>
  void set_mesh(const sim::TriMesh<Real>& mesh);
  void set_mesh(const sim::IndexedMesh& mesh);
  /// The liquid mask to shade on the ground (nullptr = none). Must outlive render().
  void set_liquid(const sim::LiquidMask* mask) { mask_ = mask; }

  /// Renders a frame: linear RGB, camera width × height.
  RgbImage render();
  /// The plan render() would use now.
  ShadingPlan plan() const;

  const RenderScene& scene() const { return scene_; }
  const Camera& camera() const;
  const FrameStats& last_stats() const { return stats_; }
  const RgbImage& environment() const { return env_; }

 private:
  void resolve_defaults();

  RenderScene scene_;
  std::optional<Camera> camera_;
  MeshBvh bvh_;
  const sim::LiquidMask* mask_ = nullptr;
  RgbImage env_, ground_tex_, normal_tex_, ice_tex_;  ///< ice_tex_: empty = the procedural milky ice
  std::unique_ptr<FilteredTextures> filtered_;        ///< texture_filter: mipmap
  std::unique_ptr<fog::FogShader> fog_;               ///< scene `fog:` (fog/scene_fog.h)
  int env_id_ = -1, ground_id_ = -1, normal_id_ = -1, ice_id_ = -1;
  bool sized_ = false;
  double object_size_ = 1.0;
  std::string last_plan_log_;
  FrameStats stats_;
};

}  // namespace meltlab::render
