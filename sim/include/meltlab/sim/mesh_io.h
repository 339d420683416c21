#pragma once
// Mesh files: OBJ, PLY, OFF and STL, read and written through OpenMesh's IO layer.
// Reading keeps the file's polygons as they are (no topology is built by OpenMesh, so
// nothing is silently dropped); welding, triangulation and validation are ours, and every
// refusal is one line naming the file and the offending vertex/edge.

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/polygon_mesh.h>
#include <meltlab/sim/topology.h>

#include <filesystem>
#include <string>
#include <vector>

namespace meltlab::sim {

/// Reads the polygons of a mesh file as stored (format from the extension, case-insensitive:
/// .obj .ply .off .stl). Throws InputError "<file>: <problem>" if the file is missing,
/// unreadable, of an unknown format, empty, has out-of-range indices or non-finite
/// coordinates (naming the first bad vertex).
PolygonMesh read_polygon_mesh(const std::filesystem::path& file);

struct LoadOptions {
  double weld_tolerance = 0.0;  ///< merge vertices closer than this (mesh units); 0 = identical only
  bool repair = false;          ///< repair open/non-manifold/misoriented input with CGAL instead of refusing
  bool validate = true;         ///< refuse invalid meshes; false returns them anyway (diagnostics)
};

struct LoadReport {
  std::size_t file_vertices = 0;
  std::size_t file_faces = 0;
  std::size_t welded_vertices = 0;
  std::size_t unreferenced_vertices = 0;
  std::size_t degenerate_faces = 0;
  EulerCounts file_counts;           ///< Eq. 2.3 counts of the welded polygon mesh
  std::vector<std::string> repairs;  ///< what --repair changed (empty if nothing)
};

struct LoadedMesh {
  IndexedMesh mesh;      ///< triangulated, welded, validated (closed, manifold, oriented) unless !validate
  PolygonMesh polygons;  ///< welded polygons as in the file (for Tab. 2.3-style counts)
  LoadReport report;
};

/// Reads, welds, triangulates and validates a closed solid. Without `repair`, an open,
/// non-manifold or inconsistently oriented mesh is refused with InputError naming the file
/// and the first problem ("<file>: open mesh: boundary edge (v3, v17)").
LoadedMesh load_mesh(const std::filesystem::path& file, const LoadOptions& options = {});

/// Writes a triangle mesh (format from the extension). Atomic: written to a temporary file
/// in the same folder, then renamed. Throws InputError on failure.
void save_mesh(const IndexedMesh& mesh, const std::filesystem::path& file);

/// Lower-case extension without the dot, e.g. "off".
std::string mesh_format_of(const std::filesystem::path& file);

}  // namespace meltlab::sim
