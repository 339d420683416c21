#pragma once
// Ray tracer of melting ice on a wet ground (monograph chapters 6-7, spec §7-8), on the CPU:
// an Embree BVH over the current mesh (refitted or rebuilt each cycle), primary rays from a
// camera.h camera (one ray per pixel centre), image tiles of 16×16 pixels in parallel (TBB).
//
// A primary ray that meets the ice is shaded by the ice material (material/ice.h: the
// monograph's Eq. 6.11 with the normal map of Eq. 6.12, or the physical reference, which
// follows its rays through the ice by asking this tracer for the crossings of the surface and
// the radiance from outside it); one that meets the ground plane z = ground.z is shaded by the
// ground with its liquid (material/ground.h, Eq. 7.17); anything else, and a ray meeting the
// ground beyond 10⁶ object sizes (the horizon), sees the environment. Secondary rays of the
// physical ice that meet the ice again see its environment value (no further recursion). No
// shadows and no ice seen through the ground, as in the monograph.
// Fog (scene `fog:`, seed 002): after a pixel is shaded, fog/scene_fog.h's FogShader attenuates
// it by e^{-k_t m} (m: the first surface, ice or ground, or the fog's `far`) and adds each
// spotlight's airlight and surface terms with the hit material's Phong coefficients.
//
// Texture lookups (scene `texture_filter`, texture/lookup.h): the materials look their
// textures up through one interface, bilinear or MIP-mapped. Only for MIP-mapped lookups does
// the tracer compute footprints: ray differentials of the primary rays (the rays through the
// next pixel to the right and below, ray_differential.h), carried to the ground plane and to
// the ice's tangent plane; the materials carry them through reflection and refraction.
//
// Skip what the scene does not need (design.md): the materials plan which of their terms a
// frame computes (plan_ice, plan_ground: terms with a zero weight, the liquid when the mask is
// dry or absent, dispersion with equal indices); plan() lists what is skipped; it is logged
// once per change of plan.

#include <meltlab/render/camera.h>
#include <meltlab/render/embree/mesh_bvh.h>
#include <meltlab/render/material/ground.h>
#include <meltlab/render/material/ice.h>
#include <meltlab/render/render_scene.h>
#include <meltlab/render/texture/lookup.h>
#include <meltlab/sim/liquid_mask.h>

#include <memory>
#include <string>
#include <vector>

namespace meltlab::render {

namespace fog {
class FogShader;
}

/// Which terms a frame computes (from the scene's weights and the current mask).
struct ShadingPlan : IcePlan, GroundPlan {
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

 private:
  void resolve_defaults();

  RenderScene scene_;
  std::optional<Camera> camera_;
  MeshBvh bvh_;
  const sim::LiquidMask* mask_ = nullptr;
  bool footprints_ = false;  ///< the lookups use footprints (texture_filter: mipmap)
  std::unique_ptr<const EnvironmentTexture> environment_;
  std::unique_ptr<const ImageTexture> ground_texture_, normal_map_;
  std::unique_ptr<const ImageTexture> ice_texture_;  ///< nullptr: the procedural milky ice
  std::unique_ptr<fog::FogShader> fog_;              ///< scene `fog:` (fog/scene_fog.h)
  bool sized_ = false;
  double object_size_ = 1.0;
  std::string last_plan_log_;
  FrameStats stats_;
};

}  // namespace meltlab::render
