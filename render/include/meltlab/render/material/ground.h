#pragma once
// The ground of the ray tracer (integrator/ice_surface.h) and the liquid on it (monograph
// chapter 7): the plane z = ground.z, normal +z, seen at the point q along direction d.
//
// The liquid (LiquidFilm), Eq. 7.17 with w = step(p, mask) at the point's texel (Eq. 7.7 on the
// bilinear mask and threshold, texel centres at integers, texels beyond the grid dry) and the
// rim normal from the neighbours one texel away (Eq. 7.3):
//   N* = normalize([tilt_s·(w_left - w_right), tilt_t·(w_down - w_up), 1])  (w_down at t-1)
// The ground (WetGround):
//   t*diff = tdiff(s - d·Vx·w, t - d·Vy·w)      (s, t in ground-texture periods)
//   I = ((ca + Σ Izr·cd·max(0, N*·L))·t*diff + Σ Izr·cs·max(0, Rs·V)^n)^(1 + a·w) + cr·tenv(R*e)·w
//   (the base is clamped at 0 before the power; values above 1 — highlights — are not clamped)
//   Rs and R*e use N* (`rs_uses_n_star`). Without a mask (or with no texel at or above p, or
//   ground.liquid off) the ground is plain Phong (Eq. 2.13) × tdiff.
// No shadows and no ice seen through the ground, as in the monograph.
// Footprints (texture_filter: mipmap): the ground texture with the footprint of q, the
// reflection with that of d mirrored about N* (the rim normal's own change is not followed).

#include <meltlab/render/material/shading.h>
#include <meltlab/render/texture/lookup.h>
#include <meltlab/sim/liquid_mask.h>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::render {

/// The ground parameters of the render scene (render_scene.h reads them).
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

/// Which terms of the ground a frame computes.
struct GroundPlan {
  bool liquid = false, liquid_rim = false, liquid_offset = false, liquid_reflection = false, ground_specular = true;
};
/// No specular if cs = 0 or there is no light; no liquid when ground.liquid is off, there is
/// no mask, nothing of it would show (a = cr = tilt = d = 0) or no texel is at or above the
/// threshold; then no rim normals if tilt = 0, no film offset if d = 0, no reflection if cr = 0.
/// What is skipped is appended to `skipped`.
GroundPlan plan_ground(const GroundMaterial& ground, bool lit, const sim::LiquidMask* mask,
                       std::vector<std::string>& skipped);

/// The liquid on the ground at a point: the wet test w (0 or 1) and the rim normal N*.
class LiquidFilm {
 public:
  struct At {
    double w = 0;                                  ///< step(p, mask) (Eq. 7.7)
    Eigen::Vector3d n = Eigen::Vector3d(0, 0, 1);  ///< N* (Eq. 7.3); +z without `rim`
  };
  /// `mask` must outlive the film. `rim`: compute N* (else the ground stays flat).
  LiquidFilm(const sim::LiquidMask& mask, double tilt_s, double tilt_t, bool rim);
  At at(const Eigen::Vector3d& q) const;

 private:
  double mask_bilinear(const std::vector<float>& v, double tx, double ty, bool zero_outside) const;
  double wet(double tx, double ty) const;  ///< step(p, mask) at texel coordinates

  const sim::LiquidMask& mask_;
  double tilt_s_, tilt_t_;
  bool rim_;
  std::vector<std::uint8_t> wet_window_;  ///< per texel (see the .cpp), empty if not usable
};

/// The ground with its liquid (above).
class WetGround {
 public:
  /// `mask`: the liquid (nullptr: none); it, the material, the lights and the textures must
  /// outlive the ground. `tdiff` is looked up only if `ground.textured`.
  WetGround(const GroundMaterial& ground, const GroundPlan& plan, const std::vector<Light>& lights,
            const ImageTexture& tdiff, const EnvironmentTexture& environment, const sim::LiquidMask* mask);
  /// The radiance from ground point q towards the eye along -d; `dq`, `dd`: the footprint of q
  /// and of d (nullptr: none).
  Rgb shade(const Eigen::Vector3d& q, const Eigen::Vector3d& d, const Differential* dq, const Differential* dd) const;

  /// What the fog's surface terms (fog/scene_fog.h) see of ground point q viewed along d: the
  /// diffuse colour t*diff — the texture, shifted by the liquid film exactly as in `shade` — and
  /// the normal (the film's N* where wet, +z elsewhere). `dq`: q's footprint (nullptr: none).
  struct FogSurface {
    Rgb diffuse_colour = Rgb(1, 1, 1);
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  };
  FogSurface fog_surface(const Eigen::Vector3d& q, const Eigen::Vector3d& d, const Differential* dq) const;

 private:
  /// t*diff at q seen from V (unit, towards the eye) with the film's weight w (Eq. 7.5).
  Rgb texture_at(const Eigen::Vector3d& q, const Eigen::Vector3d& V, double w, const Differential* dq) const;

  const GroundMaterial& material_;
  GroundPlan plan_;
  const std::vector<Light>& lights_;
  const ImageTexture& tdiff_;
  const EnvironmentTexture& environment_;
  std::optional<LiquidFilm> liquid_;  ///< if the plan has the liquid
};

}  // namespace meltlab::render
