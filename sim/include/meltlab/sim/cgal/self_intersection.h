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
  std::size_t pairs = 0;                        ///< intersecting triangle pairs found (up to the cap)
  std::vector<std::pair<Index, Index>> sample;  ///< first few pairs, as triangle slot indices
};

/// Tests the live triangles of `m` for self-intersections (pairs that share a vertex are
/// not counted unless they overlap beyond it). Stops counting at `max_pairs`.
template <class Real>
SelfIntersectionReport self_intersections(const TriMesh<Real>& m, std::size_t max_pairs = 1000);

}  // namespace meltlab::sim
