#pragma once
// Closed triangle mesh -> volume fraction per cell of a Grid3.
//
// Method: parity of ray crossings along +z. Each column (i, j) is sampled by S x S rays at
// the sub-cell centres (slightly jittered by a fixed irrational offset so that rays do not
// hit mesh edges/vertices exactly); the sorted z of a ray's crossings with the mesh pair up
// into inside intervals, and each interval adds its overlap with cell k, divided by h S², to
// the cell. Exact along z, sampled in x and y: the volume error is O(h² / S · perimeter) for
// smooth shapes. Triangles are binned to columns by their xy bounding box. The mesh must be
// closed (a watertight solid); its orientation does not matter.

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/physics/ice_fraction.h>

#include <cstdint>

namespace meltlab::sim::physics {

struct VoxelizeOptions {
  double h_m = 2e-3;     ///< cell edge, same units as the mesh (metres for molds)
  int margin_cells = 2;  ///< empty cells around the mesh's bounding box
  /// Put the grid floor exactly at the mesh's lowest z (no margin below): the body then
  /// rests on the solver's ground (layer k = 0). Else the margin applies below too.
  bool floor_at_mesh_bottom = true;
  int subsamples = 4;  ///< S: rays per cell edge (S² per column cell)
};

/// Builds a grid around `mesh` and fills it with the volume fraction of each cell.
Grid3<float> voxelize_fraction(const IndexedMesh& mesh, const VoxelizeOptions& options = {});

/// Fills an existing grid (its geometry is kept, values overwritten).
void voxelize_into(const IndexedMesh& mesh, Grid3<float>& grid, int subsamples = 4);

/// fraction >= 0.5 -> 1.
Grid3<std::uint8_t> voxelize_occupancy(const IndexedMesh& mesh, const VoxelizeOptions& options = {});

/// Σ fraction · h³.
double grid_volume(const Grid3<float>& fraction);

}  // namespace meltlab::sim::physics
