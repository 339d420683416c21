#pragma once
// The body of ice the physically based reference solver melts (sim/physics): a closed mesh
// scaled to a mass of ice, centred over the origin, standing on the ground (z = 0), and
// voxelised for the enthalpy solver. `meltlab predict` builds its body here; `meltlab
// manufacture` does the same steps inline (the same arithmetic, so that both predict the
// same melt bit for bit: tests/cli/predict_test.sh checks it).

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/physics/enthalpy.h>

#include <Eigen/Core>

#include <string>

namespace meltlab::experiments {

struct PhysicsBody {
  sim::IndexedMesh mesh;  ///< metres, scaled and placed
  double scale = 1;       ///< applied to the source mesh's coordinates
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  Grid3<float> fraction;  ///< ice fraction per cell (the solver's initial state)
};

/// Scales `mesh` (any units) to `mass_g` of ice of the density of `physics`, puts it on the
/// ground and voxelises it at `voxel_mm` (3 cells of margin, the grid floor at the body's
/// bottom). Throws InputError naming `source` for a mesh that encloses no volume.
PhysicsBody make_physics_body(sim::IndexedMesh mesh, double mass_g, double voxel_mm,
                              const sim::physics::IceMeltParams& physics, const std::string& source);

/// A closed mesh of a simple shape in metres from "box:WxDxH", "cylinder:DxH" or "sphere:D"
/// (millimetres; ',' may separate the numbers too). Throws InputError "--shape: ..." for
/// anything else.
sim::IndexedMesh shape_mesh(const std::string& shape);

}  // namespace meltlab::experiments
