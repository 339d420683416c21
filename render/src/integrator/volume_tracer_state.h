#pragma once
// Private to the volume integrator (volume_integrator.cpp, volume_tf.cpp): the per-render state
// behind VolumeTracer, and what the optical models share — the sample grid of a ray.

#include <meltlab/render/integrator/volume_integrator.h>

#include <cstdint>
#include <memory>
#include <optional>

namespace meltlab::render::detail {

/// A tracer's state behind a virtual interface (one dispatch per ray).
struct TracerState {
  virtual ~TracerState() = default;
  /// One ray o + t v on [t0, t1]: adds the radiance to I, returns T.
  virtual double trace(const Eigen::Vector3d& o, const Eigen::Vector3d& v, double t0, double t1, std::uint64_t pixel,
                       Rgb& I, VolumeRenderStats& st) const = 0;
  virtual double optical_depth(const Eigen::Vector3d& x, const Eigen::Vector3d& d, double max_distance,
                               std::int64_t& samples) const = 0;
  /// A whole frame, when the state renders its own (the TF model's traversals); nullopt: the
  /// integrator's per-pixel loop over trace() (seed 000's models).
  virtual std::optional<VolumeFrame> render(const Camera&) const { return std::nullopt; }
  Box3 box;
  double cache_ms = 0;
  std::int64_t cache_samples = 0;
  double index_ms = 0;
};

/// The samples of one ray: t_k = a + k h for k < n (vlr.sampling.* / clv.sampling.*).
struct SampleGrid {
  double a = 0, h = 0;
  std::int64_t n = 0;
};
SampleGrid sample_grid(const VolumeRenderSettings& s, double ds, double t0, double t1, std::uint64_t pixel_id);

/// The TF model (volume_tf.cpp).
void validate_tf(const VolumeRenderSettings& s, bool bricked);
std::unique_ptr<TracerState> make_tf_state(const Volume& volume, const VolumeRenderSettings& s,
                                           std::shared_ptr<const VolumeRangeIndex> ranges);
std::unique_ptr<TracerState> make_tf_state(const BrickedVolume& volume, const VolumeRenderSettings& s,
                                           std::shared_ptr<const VolumeRangeIndex> ranges);

}  // namespace meltlab::render::detail
