#pragma once
// The melt cycle on OpenMesh's half-edge structure: the speed peer of the benchmarks.
// It implements the same model as sim::MeltSimulator with OpenMesh's own operations, so
// "faster than OpenMesh" compares our indexed structure-of-arrays cycle with a competent,
// idiomatic half-edge implementation, not with a strawman. Never used for results.
//
// One cycle (see openmesh_peer.cpp for the measurements behind each choice):
//   Alg. 1  face normals by OpenMesh's update_face_normals() (unit, Eq. 2.9); then one
//           outgoing-half-edge circulation per vertex sums the unit normals of its faces
//           (N = the normalised sum, Eq. 2.10 — exactly what OpenMesh's
//           update_vertex_normals() computes) and the unit vectors to its neighbours
//           (M_E = their mean, Eq. 3.5), and stores the move of Eq. 3.6/3.8 with kl = 1 in
//           a vertex property. All moves use the pre-move positions; they are applied
//           after the sweep.
//   Alg. 2  edges shorter than kr are collapsed with mesh.collapse(heh) where
//           mesh.is_collapse_ok(heh), edges in index order, the higher-index endpoint
//           removed and the survivor moved to the edge midpoint. A vertex takes part in at
//           most one collapse per pass (the analogue of the monograph's one edge per
//           triangle per pass; no merge chains). Deleted elements are compacted lazily.
//   Alg. 3  not needed: is_collapse_ok (the link condition) never creates glued pairs, with
//           one exception: a component that has shrunk to a tetrahedron. Collapsing a short
//           edge of it leaves a glued pair that Alg. 3 would delete, so such a component is
//           deleted whole, counted as 1 merge + 2 degenerate + 2 glued triangles + 3 glued
//           vertices, as the monograph's cycle would count it.
//
// Known semantic differences from sim::MeltSimulator:
//   * The link condition also forbids the collapse that pinches a neck to a point, so the
//     peer never splits an object into parts (MeltSimulator does, §3.3): a neck's short
//     edges stay uncollapsed and the neck keeps thinning.
//   * Pairwise collapses only: no chains of merges within a pass, so a region full of short
//     edges needs a few more cycles to coarsen.
//   * Only DeformMode::kCombined and a constant kl = 1 (s = kg); TieRule and EdgeSumMode
//     are honoured; MergeMode does not apply (a pair's merge is its midpoint in both
//     modes); `repair` is ignored (the peer cannot produce non-manifold configurations).

#include <meltlab/sim/melt.h>
#include <meltlab/sim/mesh.h>

#include <cstdint>
#include <memory>

namespace meltlab::bench {

/// The melt cycle on an OpenMesh TriMesh whose points and normals are Real (float/double).
template <class Real>
class OpenMeshMeltPeerT {
 public:
  /// Builds the half-edge mesh from `mesh` (positions converted to Real). Throws
  /// InputError if `params` is invalid, if `params.deform` is not kCombined, or if OpenMesh
  /// rejects a face (the input must be a closed, oriented 2-manifold; see check_topology).
  OpenMeshMeltPeerT(const sim::IndexedMesh& mesh, const sim::MeltParams& params);
  ~OpenMeshMeltPeerT();
  OpenMeshMeltPeerT(OpenMeshMeltPeerT&&) noexcept;
  OpenMeshMeltPeerT& operator=(OpenMeshMeltPeerT&&) noexcept;

  /// One cycle: Alg. 1 then the short-edge collapses. Fills merged_vertices (collapses
  /// done), live_vertices, live_triangles, deform_ms and collapse_ms (the other timings are
  /// 0); the final-tetrahedron case also fills degenerate/glued counts (see above).
  sim::CycleReport step();

  /// The current mesh, compacted: live vertices in OpenMesh handle order.
  sim::IndexedMesh mesh() const;
  /// True once every triangle has melted away.
  bool empty() const;
  std::int64_t cycle() const { return cycle_; }

 private:
  struct Impl;  // the OpenMesh types stay in openmesh_peer.cpp
  std::unique_ptr<Impl> impl_;
  std::int64_t cycle_ = 0;
};

extern template class OpenMeshMeltPeerT<float>;
extern template class OpenMeshMeltPeerT<double>;

/// Single precision, like the MeltSimulator<float> it is benchmarked against.
using OpenMeshMeltPeer = OpenMeshMeltPeerT<float>;

}  // namespace meltlab::bench
