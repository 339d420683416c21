#pragma once
// OpenVDB (Debian's libopenvdb-dev) at meltlab's edge: .vdb files of a volume, and OpenVDB's own
// volume renderer (tools::VolumeRender over a sparse FloatGrid with hierarchical DDA), the peer
// the volume benchmarks run beside ours. The only files that include OpenVDB are in render/src/vdb.

#include <meltlab/core/image.h>
#include <meltlab/render/camera.h>
#include <meltlab/render/volume/volume.h>

#include <Eigen/Core>

#include <filesystem>
#include <functional>
#include <memory>
#include <string>

namespace meltlab::render {

/// Writes the volume as one FloatGrid named "density" (values, not stored numbers; active where
/// non-zero), index (i, j, k) at world origin + (i, j, k) * spacing, atomically. The placement is
/// kept in the grid's metadata ("meltlab_placement") so a round trip restores the domain.
void write_vdb(const std::filesystem::path& file, const Volume& volume);

/// Reads the FloatGrid named `grid` (or "density", or the only float grid) of a .vdb file as a
/// dense float32 volume over its active voxels' bounding box (inactive voxels inside it read as
/// the grid's background). Needs an axis-aligned linear transform (a scale and a translation).
/// Throws InputError naming the file: not a .vdb, no such grid, a rotated transform, or more
/// samples than --limits volume_samples.
Volume read_vdb(const std::filesystem::path& file, const std::string& grid = "");

/// What OpenVDB's VolumeRender computes (RayTracer.h): per primary sample (a multiple of the step
/// along each active span), density d, dT = exp(-σ_t d Δ), L += c_light (σ_s/σ_t) T_shadow T (1 - dT),
/// T *= dT; the shadow march to a directional light likewise; both stop below the cut-off. Steps
/// are in voxels and σ are per voxel. Its phase function is the constant 1 (not 1/4π): for the
/// same physics, its radiance is 4π times meltlab's HGAttenuated with c = 0, κ in the BRDF and
/// exponential quadrature.
struct OpenVdbRenderSettings {
  double primary_step_voxels = 1.0;
  double shadow_step_voxels = 1.0;
  double extinction_per_voxel = 0.1;  ///< σ_t = σ_s + σ_a at density 1
  double albedo = 1.0;                ///< σ_s / σ_t
  Eigen::Vector3d to_light = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d light_colour = Eigen::Vector3d::Ones();
  double cutoff = 1e-6;  ///< density below this is skipped; transmittance |T|² below it stops a ray
  bool threaded = true;
};

/// The peer: the volume converted once to a FloatGrid (the conversion is not timed per frame).
class OpenVdbPeer {
 public:
  explicit OpenVdbPeer(const Volume& volume);
  /// Seed 001's peer: a FloatGrid of density(value) per voxel (e.g. the extinction -ln(1 - α) of a
  /// transfer function at the voxel's value: classification before interpolation, as a sparse
  /// renderer has it), inactive where 0; converted in slabs of x through tools::copyFromDense
  /// (threaded), not timed per frame.
  OpenVdbPeer(const Volume& volume, const std::function<float(float)>& density);
  ~OpenVdbPeer();
  OpenVdbPeer(const OpenVdbPeer&) = delete;
  OpenVdbPeer& operator=(const OpenVdbPeer&) = delete;

  /// Renders with tools::VolumeRender through meltlab's camera (the same ray per pixel): the RGB
  /// radiance (OpenVDB's units, see above) and, in `alpha`, its 1 - mean transmittance.
  ImageF render(const Camera& camera, const OpenVdbRenderSettings& settings, ImageF* alpha = nullptr) const;
  /// Active voxels and the grid's memory.
  std::int64_t active_voxels() const;
  std::int64_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meltlab::render
