#pragma once
// Renumbering for memory locality. Scanned and exported meshes often list vertices in an
// order unrelated to where they are (CGAL's bunny00: the median triangle spans 15k of its
// 38k vertex indices), so every sweep of the melt cycle misses the cache. Sorting the
// vertices along a Morton (Z-order) curve and the triangles by their smallest vertex keeps
// neighbours close in memory.
//
// Note: Alg. 2 keeps the smaller index of a collapsed edge, so a renumbered mesh melts to
// a slightly different (equally valid) result than the same mesh in file order. The CLI
// records the choice (`--order morton|file`) in run.json.

#include <meltlab/sim/mesh.h>

#include <vector>

namespace meltlab::sim {

struct Reordered {
  IndexedMesh mesh;
  std::vector<Index> new_from_old_vertex;    ///< new index of every input vertex
  std::vector<Index> old_from_new_triangle;  ///< input index of every output triangle
};

/// Vertices in Morton order of their positions (21 bits per axis over the bounding box),
/// triangles sorted by their corners' new indices (smallest first), each triangle rotated
/// min-index first. Orientation and geometry are unchanged. O(n log n).
Reordered reorder_for_locality(const IndexedMesh& in);

}  // namespace meltlab::sim
