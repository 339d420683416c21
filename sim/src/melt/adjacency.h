#pragma once
// Private to the melt cycle: the triangles of every vertex, kept sorted by triangle index
// and updated incrementally as the cycle merges, deletes and splits. With it, every step
// after the deformation touches only the elements that changed, and the deformation
// gathers each vertex's sums in ascending triangle order — the same order for serial and
// parallel execution, so both give bitwise-identical results without atomics.
//
// Storage is one pool: vertex v owns pool[begin[v] .. begin[v] + capacity[v]) of which the
// first size[v] entries are used. A list that outgrows its block moves to the end of the
// pool; the pool is compacted when more than half of it is abandoned.

#include <meltlab/sim/mesh.h>

#include <span>
#include <vector>

namespace meltlab::sim {

class VertexTriangles {
 public:
  /// Builds the lists of the live triangles of `m` (O(n)).
  template <class Real>
  void build(const TriMesh<Real>& m);

  std::span<const Index> of(Index v) const {
    const auto vs = static_cast<std::size_t>(v);
    return {pool_.data() + begin_[vs], static_cast<std::size_t>(size_[vs])};
  }
  /// Asks the cache for v's list record (stage 1) or, once that has arrived, for the list's
  /// first entries (stage 2): the passes after the deformation visit a few scattered vertices
  /// of a large mesh, and issuing their loads a few vertices ahead overlaps the cache misses.
  void prefetch_record(Index v) const {
    const auto vs = static_cast<std::size_t>(v);
    __builtin_prefetch(begin_.data() + vs);
    __builtin_prefetch(size_.data() + vs);
  }
  void prefetch_list(Index v) const { __builtin_prefetch(pool_.data() + begin_[static_cast<std::size_t>(v)]); }
  /// Number of triangles of every vertex, indexed by vertex slot.
  std::span<const Index> counts() const { return size_; }
  std::size_t vertex_count() const { return size_.size(); }
  /// Replaces v's list by `sorted` (ascending triangle indices, no duplicates).
  void assign(Index v, std::span<const Index> sorted);
  /// Removes triangle t from v's list if present.
  void erase(Index v, Index t);
  /// Adds empty lists for vertices appended to the mesh.
  void grow(std::size_t vertex_count);
  bool built() const { return built_; }
  void invalidate() { built_ = false; }

 private:
  void compact();
  std::vector<std::size_t> begin_;
  std::vector<Index> size_, capacity_;
  std::vector<Index> pool_;
  std::size_t abandoned_ = 0;
  bool built_ = false;
};

}  // namespace meltlab::sim
