#pragma once
// Repair of invalid input meshes with CGAL's Polygon Mesh Processing (used only when the
// user asks for it with --repair; by default invalid input is refused).

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/polygon_mesh.h>

#include <string>
#include <vector>

namespace meltlab::sim {

struct RepairResult {
  IndexedMesh mesh;                  ///< closed, manifold, consistently oriented (outward)
  std::vector<std::string> actions;  ///< one line per change, e.g. "filled 2 holes (14 triangles)"
};

/// Turns a polygon soup into a closed, oriented 2-manifold triangle mesh bounding a solid:
/// repairs the soup (duplicate/degenerate polygons), orients it consistently, splits
/// non-manifold vertices, fills holes and orients the result outward.
/// Throws InputError "<source>: cannot repair: <why>" if that is impossible.
RepairResult repair_closed_solid(const PolygonMesh& in, const std::string& source);

}  // namespace meltlab::sim
