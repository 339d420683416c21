#pragma once
// Seed 002's spotlights in fog inside the Embree ice renderer (integrator/ice_surface.h): the
// `fog:` section of the render scene (render_scene.h) and the per-pixel fog pass that the
// renderer applies after shading a pixel.
//
// With a fog section, the radiance the renderer computed at the first surface (ice or ground)
// at distance m, or its background, reaches the eye attenuated as
//   L = L_shaded e^{-k_t m} + Σ_spotlights [L_a + e^{-k_t m} L_p]
// (fsa.surface.view_attenuation = apply; source_omit drops both factors e^{-k_t m}); L_a is the
// spotlight's airlight over the lit part of [0, m] (fog/airlight.h), L_p its surface terms
// (eq. 3.24: direct Phong with extinction along the light's path, and the fog's light through
// G_0 and G_n) with the hit material's Phong coefficients (ice: cd, cs, n_spec, diffuse colour
// white; ground: cd, cs, n_spec, with the ground texture's colour t*diff as the diffuse colour —
// shifted by the liquid film, looked up with the ray's footprint under texture_filter: mipmap — and
// the film's normal N* where wet). One G_n table per distinct Phong exponent (rounded to an integer
// in [1, 500]). Rays
// that hit nothing end at `far` (mesh units): the background is attenuated by e^{-k_t far}.
// No shadows (the model has none): the spotlight lights the ground through the ice.
//
// Scene keys (all optional except spotlights):
//   fog:
//     kt: 0.05                 # extinction, 1/mesh unit (fsa.medium.kt)
//     albedo: 1.0              # Ω (fsa.medium.albedo)
//     far: 1000                # mesh units
//     spotlights:
//       - {position: [x, y, z], target: [x, y, z], half_angle_deg: 30, colour: [1, 1, 1], intensity: 1,
//          rings: [{half_angle_deg: 15, intensity: 2}]}   # optional inner rings (fsa.light.profile)
//       - {kind: point, position: [x, y, z], colour: [1, 1, 1], intensity: 1}  # Sun et al.'s point light
//     table: {n: 64, function: H, u_warp: cbrt, v_warp: sqrt_hi, v_interp: value}
//                              # fsa.table.* (F|H; warps none|sqrt|cbrt|sqrt_hi|smooth; v_interp index|value)
//     view_attenuation: apply  # apply | source_omit
//     specular_args: mirror    # mirror | source
//     cone_solver: robust      # robust | source
//     only_in_cone: true       # fsa.surface.only_in_cone

#include <meltlab/render/fog/airlight.h>
#include <meltlab/render/fog/fog_frame.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace meltlab {
class ConfigSection;
}

namespace meltlab::render::fog {

struct SceneFog {
  FogMedium medium;
  double far = 1000;  ///< mesh units: where rays that hit nothing end
  std::vector<Spotlight> spotlights;
  FogModelOptions model;
  TableOptions tables;
  TableFunction function = TableFunction::kH;
};

/// Reads a `fog:` section (keys above); errors name the file, line and key.
SceneFog parse_scene_fog(const ConfigSection& fs);

/// Every choice as "fsa.*" (and fog.*) lines for the run record.
std::vector<std::pair<std::string, std::string>> describe_scene_fog(const SceneFog& f);

/// The fog pass of one frame: the tables (built once), and per pixel `apply`.
class FogShader {
 public:
  /// Builds the airlight table and G_1 and G_n for each of `phong_exponents`.
  FogShader(SceneFog fog, const std::vector<double>& phong_exponents);

  /// The pixel in fog (see the header comment): `shaded` is what the renderer computed along the
  /// ray; `hit` the first surface within `m` (nullptr: nothing hit; m is then ignored and `far`
  /// used) with its Phong material.
  Rgb apply(const Rgb& shaded, const Vec3& origin, const Vec3& dir, double m, const SurfaceHit* hit) const;

  /// The Phong material of the fog terms for Phong coefficients (kd, ks, exponent).
  static FogMaterial material(double kd, double ks, double exponent);

  const SceneFog& fog() const { return fog_; }
  /// The tables' descriptions for the run record.
  std::vector<std::string> describe() const;

 private:
  SceneFog fog_;
  FogTableSet airlight_;              ///< the airlight table (and G_1 as g_diffuse)
  std::map<int, FogTable> specular_;  ///< G_n per exponent
};

}  // namespace meltlab::render::fog
