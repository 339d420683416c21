#pragma once
// Private to the melt cycle: the order in which Alg. 1's sweep visits the mesh.
//
// The sweep runs over blocks of kTriangleBlock triangles in ascending order, computes their
// terms and adds each corner's terms to its vertex's sum record; then the vertices move,
// eight slots at a time (a "group", one SIMD lane each), in ascending order, so that the
// vertex arrays stream through the cache.
//
// Parallel sweeps split the blocks into parts, one contiguous range of blocks each, run
// side by side. Every vertex is owned by the part of its first triangle. A group whose
// vertices have all their triangles in one part is "interior" to it: that part adds into
// its records and, after its last block, moves its interior groups in ascending order. Any
// other group is a "halo" group and moves after every part has finished. Each part adds a
// triangle's terms directly into the records of the corners it owns (all of them, for a
// vertex whose triangles lie in one part); a triangle with a corner owned by an earlier
// part stores its terms instead, and in the halo phase that "split" vertex adds the stored
// terms of its triangles beyond its owner part in ascending order. A part comes after its
// owner in triangle order, so every vertex adds the same numbers in the same order as the
// serial sweep (serial and parallel cycles stay bitwise identical), and no record is
// written by two threads. Only the triangles of later parts at split vertices store terms
// (the boundary between parts once), not every triangle of a halo group.
//
// Most blocks hold no triangle with a corner owned by another part (the boundary between parts
// is short): their additions skip the owner test per corner. The schedule flags each live
// triangle with a foreign corner and counts the flags per block (block_mixed()).
//
// The schedule (the interior groups of every part, the halo groups, the owner part of every
// vertex, the flags) depends only on the triangle lists and the partition. It is kept
// across cycles and updated for the vertices whose lists changed.

#include "adjacency.h"
#include "triangle_kernels.h"

#include <meltlab/sim/melt.h>
#include <meltlab/sim/mesh.h>

#include <cstdint>
#include <span>
#include <vector>

namespace meltlab::sim {

inline constexpr std::size_t kGroup = 8;  ///< vertex slots per group of the moves (one SIMD lane each)

class DeformSchedule {
 public:
  static constexpr std::int32_t kHalo = -1;

  /// Makes the schedule match `m`, `adj` and a partition into `parts` parts: rebuilt if
  /// anything but the lists of `touched` vertices changed since the last call (or after
  /// invalidate()), else updated for the groups of the touched vertices (on the threads with
  /// kParallel: each group and each triangle is updated by one task; the same schedule).
  template <class Real>
  void update(const TriMesh<Real>& m, const VertexTriangles& adj, std::size_t parts,
              Execution exec = Execution::kSerial);
  /// Vertices whose triangle lists changed (collected until the next update()).
  void touch(std::span<const Index> vertices);
  /// Forces a rebuild at the next update() (the mesh changed in ways touch() does not cover).
  void invalidate() { valid_ = false; }

  std::size_t parts() const { return part_first_block_.size() - 1; }
  std::size_t blocks() const { return blocks_; }
  std::size_t groups() const { return group_part_.size(); }
  /// Blocks [first, last) of part p.
  std::size_t part_first_block(std::size_t p) const { return part_first_block_[p]; }
  /// The interior groups of part p, ascending: they move after the part's last block.
  std::span<const std::int32_t> interior_groups(std::size_t p) const {
    return {interior_.data() + bucket_[p], static_cast<std::size_t>(bucket_[p + 1] - bucket_[p])};
  }
  std::span<const std::int32_t> halo_groups() const { return halo_; }
  /// The part of vertex v's first triangle (0 for a vertex without triangles).
  std::size_t owner(Index v) const { return owner_[static_cast<std::size_t>(v)]; }
  const std::uint16_t* owners() const { return owner_.data(); }
  /// The part of triangle t.
  std::size_t part_of_triangle(std::size_t t) const { return block_part_[t / kTriangleBlock]; }
  /// Whether block b may hold a live triangle with a corner owned by another part. If not, every
  /// corner of its live triangles is owned by its part, and its sweep adds without testing the
  /// owners (on the bunny, the tests cost about half of what a sweep in two parts costs more
  /// than one part, on one thread). Kept exact: never false for a block with such a triangle.
  bool block_mixed(std::size_t b) const { return block_foreign_[b] != 0; }
  /// Per triangle slot: 1 if the triangle is live and has a corner owned by another part than
  /// its block's, else 0 (exact for live triangles, as block_mixed(); a dead slot may keep its
  /// flag until the next rebuild). In a mixed block only these triangles test their owners.
  const std::uint8_t* foreign() const { return foreign_.data(); }
  /// At most this many parts (the owner of a vertex is stored in 16 bits).
  static constexpr std::size_t kMaxParts = 65535;

 private:
  template <class Real>
  void rebuild(const TriMesh<Real>& m, const VertexTriangles& adj, std::size_t parts, Execution exec);
  /// owner_[v] and last_part_[v] from vertex v's list.
  template <class Real>
  void refresh_vertex(const TriMesh<Real>& m, const VertexTriangles& adj, std::size_t v);
  /// group_part_[g] from its live vertices' owner_ and last_part_; whether it changed.
  template <class Real>
  bool classify(const TriMesh<Real>& m, std::size_t g);
  void build_buckets();
  /// Whether live triangle t has a corner not owned by `part` (false for a dead slot).
  template <class Real>
  bool has_foreign_corner(const TriMesh<Real>& m, std::size_t t, std::uint16_t part) const;
  /// foreign_[t] (and its block's count, atomically: tasks update different triangles of one
  /// block) from triangle t's corners and their owners.
  template <class Real>
  void find_foreign(const TriMesh<Real>& m, std::size_t t);

  bool valid_ = false;
  std::size_t blocks_ = 0, triangles_ = 0, vertices_ = 0;
  std::vector<std::size_t> part_first_block_ = {0};
  std::vector<std::uint16_t> block_part_;
  std::vector<std::uint16_t> owner_;  ///< per vertex slot: the part of its first triangle
  /// Per vertex slot: the part of its last triangle, or kNoTriangles (dead, or without triangles).
  /// With owner_ it classifies a group without reading its vertices' lists: an update reads only
  /// the lists of the touched vertices.
  std::vector<std::uint16_t> last_part_;
  static constexpr std::uint16_t kNoTriangles = 0xFFFF;  // above any part (kMaxParts - 1)
  std::vector<std::int32_t> group_part_;                 ///< per group: the part it is interior to, or kHalo
  std::vector<std::int32_t> bucket_;                     ///< per part: first entry in interior_
  std::vector<std::int32_t> interior_;                   ///< interior groups by part, ascending
  std::vector<std::int32_t> next_;                       ///< build_buckets() scratch
  std::vector<std::int32_t> halo_;                       ///< halo groups, ascending
  std::vector<std::uint8_t> foreign_;         ///< per triangle slot: 1 if live with a corner owned by another part
  std::vector<std::uint32_t> block_foreign_;  ///< per block: its triangles with foreign_ set
  std::vector<Index> touched_groups_;         ///< update() scratch: the groups of touched_
  std::vector<Index> touched_vertices_;       ///< update() scratch: touched_ without repeats
  std::vector<std::uint8_t> vertex_seen_;     ///< update() scratch: 1 for a vertex in touched_vertices_
  std::vector<std::uint8_t> group_seen_;      ///< update() scratch: 1 for a group in touched_groups_
  std::vector<double> block_work_;            ///< rebuild() scratch
  std::vector<Index> touched_;
};

}  // namespace meltlab::sim
