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

/// The Morton order above, then breadth-first over the mesh's edges (each component from its
/// lowest index, a vertex's neighbours queued in ascending index), triangles sorted as above.
/// The two ends of an edge lie in the same or in adjacent breadth-first levels, so the window
/// of vertex records a sweep over the triangles keeps open is a few levels of the surface
/// (hundreds of vertices on a 1M-triangle scan) rather than the Morton curve's jumps: on the
/// 871k dragon the deformation runs ~1.4x faster (docs/melt-core.md). O(n log n).
Reordered reorder_breadth_first(const IndexedMesh& in);

}  // namespace meltlab::sim
