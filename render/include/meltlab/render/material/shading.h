#pragma once
// The small interface between the ice ray tracer (integrator/ice_surface.h) and the materials
// it shades with (material/ice.h: the monograph's and the physical ice; material/ground.h: the
// ground and the liquid on it). The integrator finds where a ray meets the ice or the ground and
// hands the material the point (SurfaceHit), the ray and its footprint; the material computes
// the radiance towards the eye with its own formula, its textures (texture/lookup.h) and the
// lights. A material that follows light beyond the surface (the physical ice) asks the
// integrator through IceSurroundings, so the materials know nothing of the BVH.

#include <meltlab/render/ray_differential.h>
#include <meltlab/render/texture/assets.h>

#include <Eigen/Core>

#include <cmath>
#include <optional>

namespace meltlab::render {

/// A directional light as the materials see it.
struct Light {
  Eigen::Vector3d to_light;  ///< unit direction towards the light (L)
  Rgb colour;                ///< Izr: multiplies ca, cd and cs
};

/// Where a ray meets the ice, as the integrator found it.
struct SurfaceHit {
  Eigen::Vector3d p;   ///< the point
  Eigen::Vector3d ng;  ///< unit geometric normal of the triangle (picks the axis of the projected textures)
  Eigen::Vector3d n;   ///< interpolated unit vertex normal, outward
  Differential dn;     ///< the change of n across the footprint of p (zero without a footprint)
};

/// The next crossing of the ice surface along a ray.
struct SurfaceCrossing {
  double t = 0;       ///< ray parameter (the direction is unit: a distance), mesh units
  Eigen::Vector3d n;  ///< interpolated unit vertex normal there, outward
};

/// What an ice material may ask of the integrator that calls it.
class IceSurroundings {
 public:
  virtual ~IceSurroundings() = default;
  /// The first crossing of the ice surface along o + t·d (d unit), t in (t_min, ∞).
  virtual std::optional<SurfaceCrossing> next_crossing(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                                       double t_min) const = 0;
  /// The radiance arriving at o along the secondary ray o + t·d from the scene outside the ice
  /// (ground or environment; the ice itself, if the ray meets it again, gives its environment
  /// value: no further recursion). `rd`: the ray's footprint or nullptr.
  virtual Rgb radiance_outside(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const RayDifferential* rd) const = 0;
};

/// max(0, x)^e (e >= 0; 0^0 = 1 as std::pow), without calling pow for the many non-positive
/// bases: the specular lobes.
inline double pow_pos(double x, double e) { return x > 0 ? std::pow(x, e) : (e == 0 ? 1.0 : 0.0); }

/// Per-channel power x^e for x >= 0 (the liquid's darkening exponent, Eq. 7.17).
inline Rgb pow_rgb(const Rgb& x, double e) { return Rgb(pow_pos(x.x(), e), pow_pos(x.y(), e), pow_pos(x.z(), e)); }

}  // namespace meltlab::render
