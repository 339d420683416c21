#pragma once
// `meltlab manufacture`: a photo-like observation sequence of a physically based melt
// (sim/physics: enthalpy solver) — data the empirical model did not produce (issue 4).
//
// The mesh (a mold or any closed mesh) is scaled to the requested ice mass, put on the
// ground (z = 0) and voxelised; the solver melts it in warm air on an absorbent ground and
// every interval a perspective camera above it takes a photo (render/integrator/ice_photo.h:
// absorption and scattering in the ice, textured ground, blur, noise, JPEG).
//   DIR/frames/frame_0001.jpg ...   the photos
//   DIR/manifest.yaml               observation manifest (pinhole camera, interval, defaults)
//   DIR/mass.csv                    time_s, mass_g of the ice (the weighing experiment)
//   DIR/truth/truth.json            parameters, per frame: time, mass, volume, true outline; provenance
//                                   area, and the P of the default segmentation against it
//   DIR/truth/masks/frame_NNNN.png  true outlines: silhouette of the ice surface (the ½ level
//                                   of the solid fraction, marching tetrahedra)
//   DIR/truth/initial_mesh.ply      the scaled mesh at t = 0 (path B's "plaster cast")
//   DIR/truth/meshes/frame_NNNN.ply ice surface (marching tetrahedra) every K-th photo
// The manifest is written last.

#include <meltlab/render/integrator/ice_photo.h>
#include <meltlab/sim/physics/enthalpy.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct ManufactureOptions {
  std::string mesh;                     ///< dataset name or file (metres after scaling)
  double mass_g = 250.0;                ///< §8.2: about 250 g of ice
  int photos = 200;                     ///< §8.2: about 200 photos
  double interval_s = 40.0;             ///< §8.2: a photo every 40 s
  double voxel_mm = 2.5;                ///< solver grid spacing
  sim::physics::IceMeltParams physics;  ///< air 30 °C, ice -10 °C, ground contact, ...
  int width = 1024, height = 768;
  double camera_height_m = 0.8;  ///< camera above the ground, looking down
  double fill = 0.6;             ///< fraction of the image the object spans
  render::IcePhotoOptions photo;
  int jpeg_quality = 90;
  int mesh_every = 10;  ///< write the ice surface every K-th photo (0 = never)
  std::uint64_t seed = 1;
  std::filesystem::path out_dir;
  bool overwrite = false;
  std::vector<std::string> command_line;  ///< argv, recorded in the provenance of the run record
};

struct ManufactureProgress {
  int done = 0, total = 0;
  double time_s = 0, mass_g = 0;
};

/// Generates the sequence; throws InputError on bad options before writing anything.
void manufacture_sequence(const ManufactureOptions& options,
                          const std::function<void(const ManufactureProgress&)>& progress = {});

}  // namespace meltlab::experiments
