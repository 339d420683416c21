#pragma once
// A validating pass over a mesh file BEFORE OpenMesh reads it. OpenMesh trusts what a file
// declares: a negative or huge vertex count in an OFF header, or a face list claiming four
// billion corners in a binary PLY, makes it allocate without bound. This pass reads the file
// once, without storing it, and refuses (InputError, "<file>:<line>: ..." where a line exists)
//   - counts that are negative, overflow, or exceed input_limits().mesh_elements;
//   - counts that need more bytes than the file holds (a lying or truncated header);
//   - records with fewer values than they declare, non-finite coordinates, corner counts
//     outside [3, what the record holds];
// so that whatever OpenMesh then allocates is bounded by the file's size.

#include <cstdint>
#include <filesystem>
#include <string>

namespace meltlab::sim::io {

struct DeclaredCounts {
  std::int64_t vertices = -1;  ///< -1: the format declares none (OBJ, ASCII STL: counted)
  std::int64_t faces = -1;
};

/// Checks the file of format `ext` ("off", "ply", "obj", "stl"; lower case) whose size is
/// `file_size` bytes. Throws InputError naming the file and the problem.
DeclaredCounts prescan_mesh_file(const std::filesystem::path& file, const std::string& ext, std::int64_t file_size);

}  // namespace meltlab::sim::io
