#pragma once
// Refinement of a real mesh to a larger triangle budget, for rendering benchmarks that need
// the monograph's big meshes (Tab. 6.1: a ≈871k-triangle dragon) from the smaller real
// meshes of CGAL's archive: `loop_levels` steps of Loop subdivision (OpenMesh's LoopT: smooth,
// every triangle split into four), then, to meet `target_triangles` exactly, the longest edges
// split at their midpoints, each split adding two triangles. Orientation, closedness and
// genus are kept.

#include <meltlab/sim/mesh.h>

#include <cstdint>

namespace meltlab::datasets {

/// The refined mesh. `mesh` must be a closed, manifold, consistently oriented triangle mesh.
/// `target_triangles` (0 = no edge splits) must not be below the count after subdivision,
/// F·4^loop_levels, and must differ from it by an even number (each split adds two). Throws
/// InputError on a bad argument or a mesh OpenMesh cannot take as a manifold.
sim::IndexedMesh refined(const sim::IndexedMesh& mesh, int loop_levels, std::int64_t target_triangles);

}  // namespace meltlab::datasets
