#pragma once
// Optional geometric validator: self-intersection test through CGAL's Polygon Mesh
// Processing (exact predicates). Not used in the melt cycle (the monograph's §1.2 excludes
// it for speed); used by `mesh-info`, the stress tests and `simulate --check-intersections`.

#include <meltlab/sim/mesh.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace meltlab::sim {

struct SelfIntersectionReport {
  bool intersects = false;
  std::size_t pairs = 0;  ///< intersecting triangle pairs found (up to the cap)
  /// The pairs found (all `pairs` of them, so at most max(max_pairs, 1)), as triangle SLOT
  /// indices (i, j) with i <= j, sorted. (t, t) marks a degenerate triangle t (its three
  /// corners are collinear, so it has no plane to test; counted as self-intersecting, as
  /// CGAL's Polygon Mesh Processing does).
  std::vector<std::pair<Index, Index>> sample;
};

/// Tests the live triangles of `m` for self-intersections, exactly (CGAL exact predicates on
/// the stored coordinates; float positions are converted to double without rounding).
///
/// Two triangles intersect if they have a common point other than what they share by
/// construction: triangles sharing an edge (the same two vertex slots) count only if they
/// are coplanar and fold onto each other; triangles sharing a vertex slot count only if
/// they meet beyond it; triangles with the same three slots always count. Triangles that
/// merely touch (distinct slots at the same position, an edge on a face) do count.
///
/// Works on any live triangle set, manifold or not: non-manifold edges and vertices,
/// mixed orientation, duplicate faces and live triangles on dead vertex slots (whose
/// positions are still stored) are all tested as they are. Dead triangle slots are ignored.
///
/// Stops at `max_pairs` pairs (0 is treated as 1, so `intersects` is always meaningful).
/// Cost: O(n log n + k) for n live triangles and k overlapping bounding-box pairs,
/// single-threaded (about 80 ms for an 82k-triangle sphere).
///
/// Throws InvariantError if a live triangle uses a vertex index outside [0, #slots) or a
/// vertex at a non-finite position (nothing can be decided about such a triangle).
template <class Real>
SelfIntersectionReport self_intersections(const TriMesh<Real>& m, std::size_t max_pairs = 1000);

}  // namespace meltlab::sim
