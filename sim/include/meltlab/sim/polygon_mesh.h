#pragma once
// General polygon mesh: faces are vertex loops, optionally with inner loops (holes in a
// face, the H of Eq. 2.3). This is the form meshes are read in (a quad cube stays 6 quads
// for its Euler counts) and the form of the monograph's Tab. 2.3 examples. Melting works on
// TriMesh; `triangulate` converts.

#include <meltlab/sim/mesh.h>

#include <string>
#include <vector>

namespace meltlab::sim {

struct PolygonFace {
  std::vector<Index> outer;               ///< CCW seen from outside the solid
  std::vector<std::vector<Index>> holes;  ///< inner loops (CW seen from outside); usually empty
};

struct PolygonMesh {
  std::vector<Vec3<double>> V;  ///< positions, object frame, mesh units
  std::vector<PolygonFace> faces;

  std::size_t hole_count() const;
  bool has_holes() const { return hole_count() > 0; }
};

/// Result of welding: the mesh with duplicate vertices merged and the count merged.
struct WeldResult {
  PolygonMesh mesh;
  std::size_t merged_vertices = 0;           ///< vertices removed as duplicates
  std::size_t unreferenced_removed = 0;      ///< vertices used by no face, dropped
  std::size_t degenerate_faces_removed = 0;  ///< faces left with < 3 distinct corners
};

/// Merges vertices whose positions coincide within `tolerance` (mesh units; 0 = bitwise
/// equal), drops vertices no face uses and faces that collapse to fewer than 3 distinct
/// corners. Keeps the first occurrence's position. O(n log n).
WeldResult weld_vertices(const PolygonMesh& in, double tolerance = 0.0);

/// Fan-triangulates every face (faces with holes are refused: they exist only in Tab. 2.3
/// examples). Throws InputError naming `source` if a face has holes.
IndexedMesh triangulate(const PolygonMesh& in, const std::string& source = "mesh");

/// Polygon view of a triangle mesh (live elements only, compacted).
PolygonMesh to_polygon_mesh(const IndexedMesh& m);

}  // namespace meltlab::sim
