#pragma once
// A validating pass over a mesh file BEFORE OpenMesh reads it (and our own OFF reader). OpenMesh trusts what a file
// declares: a negative or huge vertex count in an OFF header, or a face list claiming four
// billion corners in a binary PLY, makes it allocate without bound. This pass reads the file
// once, without storing it, and refuses (InputError, "<file>:<line>: ..." where a line exists)
//   - counts that are negative, overflow, or exceed input_limits().mesh_elements;
//   - counts that need more bytes than the file holds (a lying or truncated header);
//   - records with fewer values than they declare, non-finite coordinates, corner counts
//     outside [3, what the record holds];
// so that whatever OpenMesh then allocates is bounded by the file's size.

#include <meltlab/sim/polygon_mesh.h>

#include <cstdint>
#include <filesystem>
#include <string>

namespace meltlab::sim::io {

struct DeclaredCounts {
  std::int64_t vertices = -1;  ///< -1: the format declares none (OBJ, ASCII STL: counted)
  std::int64_t faces = -1;
};

/// Checks the file of format `ext` ("ply", "obj", "stl"; lower case) whose size is `file_size`
/// bytes before OpenMesh reads it. Throws InputError naming the file and the problem.
DeclaredCounts prescan_mesh_file(const std::filesystem::path& file, const std::string& ext, std::int64_t file_size);

/// Reads an OFF file ([ST][C][N]OFF, ASCII or BINARY) itself: OpenMesh's OFF reader reads counts
/// and corner lists from a token stream it cannot be kept from trusting. '#' comments, counts on
/// the OFF line or the next ones, extra values per vertex or face (normals, colours) ignored;
/// coordinates stored as OpenMesh stored them (float, widened to double). Throws InputError.
PolygonMesh read_off(const std::filesystem::path& file, std::int64_t file_size);

}  // namespace meltlab::sim::io
