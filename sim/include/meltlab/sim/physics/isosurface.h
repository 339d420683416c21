#pragma once
// Ice surface from a fraction field: marching tetrahedra at an iso level on the lattice of
// cell centres, each lattice cube split into the 6 tetrahedra of the Kuhn (Freudenthal)
// decomposition (all sharing the cube diagonal (0,0,0)-(1,1,1)). The decomposition is the
// same in every cube, so neighbouring cubes' tetrahedra meet face to face and the surface is
// watertight and manifold without ambiguity tables. The grid is padded with a layer of zeros
// on every side, so the surface is closed. Vertices lie on lattice edges (interpolated
// linearly, the parameter clamped to [1e-4, 1 - 1e-4] so no triangle collapses to a point
// and values equal to the level do not create coincident vertices) and are welded by edge.
// Triangles are oriented counter-clockwise seen from outside (normals towards lower values).
// A triangle never repeats a vertex (its vertices lie on distinct edges).
//
// The result: closed, manifold, oriented outward (check_topology(...).valid()), one component
// per connected region of the inside cells (>= level), possibly of genus > 0.

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/physics/ice_fraction.h>

namespace meltlab::sim::physics {

/// Surface {fraction = level}, positions in the grid's world frame (metres).
IndexedMesh isosurface(const Grid3<float>& fraction, double level = 0.5);

}  // namespace meltlab::sim::physics
