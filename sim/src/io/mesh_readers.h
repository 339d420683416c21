#pragma once
// Our readers of OFF, PLY, OBJ and STL (mesh_io.cpp picks one by extension).
//
// Why not OpenMesh's readers (OpenMesh still writes meshes): they trust what a file declares. A
// negative or huge count in an OFF header, a face list claiming a billion corners, a PLY header
// they loop on, an OBJ face with an empty index -- each made them allocate without bound, hang or
// crash under fuzzing (tests/fuzz/regressions/). These readers
//   - check every declared count against the file's size and input_limits().mesh_elements before
//     they allocate, and refuse negative, overflowing or lying counts;
//   - refuse records with fewer values than they declare, non-finite coordinates, corner counts
//     below 3, and vertex indices out of range, naming "<file>:line N" (text) or the element;
//   - store coordinates as OpenMesh's readers did (a float, widened to double), so meshes read
//     before these readers existed keep their bits, and STL corners that are equal floats become
//     one vertex in the order they first appear, as in OpenMesh.

#include <meltlab/sim/polygon_mesh.h>

#include <cstdint>
#include <filesystem>

namespace meltlab::sim::io {

/// [ST][C][N]OFF, ASCII or BINARY (little-endian, without colours). '#' comments, counts on the
/// OFF line or the next ones, extra values per vertex or face (normals, colours) ignored.
PolygonMesh read_off(const std::filesystem::path& file, std::int64_t file_size);
/// PLY 1.0, ascii / binary_little_endian / binary_big_endian; element `vertex` (x, y, z of any
/// numeric type) and `face` (list vertex_indices or vertex_index); other elements and
/// properties (scalars or lists) skipped.
PolygonMesh read_ply(const std::filesystem::path& file, std::int64_t file_size);
/// Wavefront OBJ: `v x y z [...]`, `f i[/t][/n] ...` with 1-based or negative (relative)
/// indices; every other statement ignored.
PolygonMesh read_obj(const std::filesystem::path& file);
/// STL: binary exactly when the size is 84 + 50 * (count at byte 80), else ASCII.
PolygonMesh read_stl(const std::filesystem::path& file, std::int64_t file_size);

}  // namespace meltlab::sim::io
