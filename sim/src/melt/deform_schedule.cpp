#include "deform_schedule.h"

#include "workspace.h"

#include <algorithm>
#include <atomic>
#include <cstdint>

namespace meltlab::sim {

namespace {
// Groups or touched vertices per task of an update or a rebuild on the threads (below twice this,
// one task: a 32k mesh's merges or a bunny's touch a few hundred vertices a cycle; the dragon's
// thousands), and an eighth of it in blocks of triangles.
constexpr std::size_t kUpdateGrain = 256;
}  // namespace

void DeformSchedule::touch(std::span<const Index> vertices) {
  if (valid_) touched_.insert(touched_.end(), vertices.begin(), vertices.end());
}

template <class Real>
void DeformSchedule::update(const TriMesh<Real>& m, const VertexTriangles& adj, std::size_t parts, Execution exec) {
  const std::size_t nt = m.triangle_slots();
  const std::size_t blocks = (nt + kTriangleBlock - 1) / kTriangleBlock;
  parts = std::max<std::size_t>(1, std::min({parts, blocks, kMaxParts}));
  if (!valid_ || parts != this->parts() || nt != triangles_ || m.vertex_slots() != vertices_) {
    rebuild(m, adj, parts, exec);
    return;
  }
  if (touched_.empty()) return;
  // Each touched vertex and group once. classify() writes only its own group, so the groups may
  // be classified in any order and side by side. (On the 871k dragon, which merges ~1 800 vertices
  // a cycle, the serial update took 1.3 ms of a 14.4 ms two-thread cycle while the other thread
  // waited: 0.1 ms sorting the groups, 1.05 classifying and flagging, 0.15 the buckets.)
  vertex_seen_.resize(vertices_, 0);
  group_seen_.resize(group_part_.size(), 0);
  touched_vertices_.clear();
  touched_groups_.clear();
  for (Index v : touched_) {
    const auto vs = static_cast<std::size_t>(v);
    if (vertex_seen_[vs] != 0) continue;
    vertex_seen_[vs] = 1, touched_vertices_.push_back(v);
    if (group_seen_[vs / kGroup] == 0)
      group_seen_[vs / kGroup] = 1, touched_groups_.push_back(static_cast<Index>(vs / kGroup));
  }
  for (Index g : touched_groups_) group_seen_[static_cast<std::size_t>(g)] = 0;
  std::atomic<bool> classes_changed{false};
  // The touched vertices and their lists are scattered over a large mesh: their list records and then
  // their lists are asked for a few items ahead (prefetched_for_each). Without it the classification
  // and the flags below took 0.46 and 0.64 ms of the dragon's 11-ms two-thread cycle, waiting on one
  // vertex's misses at a time; with it 0.21 and 0.31 (docs/melt-core.md, issue 20 step 26).
  for_range(
      exec, touched_groups_.size(),
      [&](std::size_t begin, std::size_t end) {
        prefetched_for_each(
            std::span<const Index>(touched_groups_).subspan(begin, end - begin),
            [&](Index g) {
              adj.prefetch_record(static_cast<Index>(static_cast<std::size_t>(g) * kGroup));
              __builtin_prefetch(m.vertex_alive.data() + static_cast<std::size_t>(g) * kGroup);
            },
            [&](Index g) {
              const std::size_t end_v = std::min(vertices_, (static_cast<std::size_t>(g) + 1) * kGroup);
              for (std::size_t v = static_cast<std::size_t>(g) * kGroup; v < end_v; ++v)
                if (vertex_seen_[v] != 0) adj.prefetch_list(static_cast<Index>(v));
            },
            [&](Index g) {
              // Only the touched vertices' lists changed: the others' owner_ and last_part_ stand.
              const std::size_t end_v = std::min(vertices_, (static_cast<std::size_t>(g) + 1) * kGroup);
              for (std::size_t v = static_cast<std::size_t>(g) * kGroup; v < end_v; ++v)
                if (vertex_seen_[v] != 0) refresh_vertex(m, adj, v);
              if (classify(m, static_cast<std::size_t>(g))) classes_changed.store(true, std::memory_order_relaxed);
            });
      },
      kUpdateGrain);
  // Whether a triangle has a corner owned by another part changes only where its corners
  // change or the owner of a corner does: either changes a vertex's triangle list (the owner is
  // the part of the first triangle), so the triangle is in the (new) list of a touched vertex.
  // (A triangle that died keeps its flag until the next rebuild: its block only stays tested.)
  // Each triangle is flagged once, from its smallest touched corner (all owners are final here).
  for_range(
      exec, touched_vertices_.size(),
      [&](std::size_t begin, std::size_t end) {
        prefetched_for_each(
            std::span<const Index>(touched_vertices_).subspan(begin, end - begin),
            [&](Index v) { adj.prefetch_record(v); }, [&](Index v) { adj.prefetch_list(v); },
            [&](Index v) {
              for (Index t : adj.of(v)) {
                // A corner's owner is the part of its first triangle, so no later than the part of
                // any of its triangles: a triangle of part 0 never has a foreign corner (nor a flag).
                if (block_part_[static_cast<std::size_t>(t) / kTriangleBlock] == 0) continue;
                const Triangle& tri = m.triangle[static_cast<std::size_t>(t)];
                bool first = true;
                for (Index c : tri) first = first && !(c < v && vertex_seen_[static_cast<std::size_t>(c)] != 0);
                if (first) find_foreign(m, static_cast<std::size_t>(t));
              }
            });
      },
      kUpdateGrain);
  for (Index v : touched_vertices_) vertex_seen_[static_cast<std::size_t>(v)] = 0;
  touched_.clear();
  // The lists of groups by part follow the classes (on the dragon, ~3 500 groups touched a cycle,
  // most keep their class; the lists are a pass over all ~55 000 groups).
  if (classes_changed.load(std::memory_order_relaxed)) build_buckets();
}

template <class Real>
bool DeformSchedule::has_foreign_corner(const TriMesh<Real>& m, std::size_t t, std::uint16_t part) const {
  const Triangle& tri = m.triangle[t];
  return m.triangle_alive[t] != 0 &&
         ((owner_[static_cast<std::size_t>(tri[0])] != part) | (owner_[static_cast<std::size_t>(tri[1])] != part) |
          (owner_[static_cast<std::size_t>(tri[2])] != part));
}

template <class Real>
void DeformSchedule::find_foreign(const TriMesh<Real>& m, std::size_t t) {
  const bool foreign = has_foreign_corner(m, t, block_part_[t / kTriangleBlock]);
  if (foreign != (foreign_[t] != 0)) {
    foreign_[t] = foreign ? 1 : 0;
    std::atomic_ref<std::uint32_t> count(block_foreign_[t / kTriangleBlock]);
    if (foreign)
      count.fetch_add(1, std::memory_order_relaxed);
    else
      count.fetch_sub(1, std::memory_order_relaxed);
  }
}

template <class Real>
void DeformSchedule::rebuild(const TriMesh<Real>& m, const VertexTriangles& adj, std::size_t parts, Execution exec) {
  triangles_ = m.triangle_slots();
  vertices_ = m.vertex_slots();
  blocks_ = (triangles_ + kTriangleBlock - 1) / kTriangleBlock;
  // Equal work per part: a part sweeps its blocks' live triangles and moves the vertices it
  // owns (those whose first triangle is in it), a move costing about kMoveWeight triangles.
  // Equal numbers of blocks could leave one part far more vertices: on object C after 20
  // cycles (merges, a compaction) the first half of the blocks held 63 % of the interior groups.
  // (The work is counted in integers: the live triangles of each block, then the vertices whose
  // first triangle it holds, each vertex of a run in one block counted in a register. Adding 1.0
  // and 0.5 into block_work_ one at a time made each addition wait on the store of the one before:
  // the two loops took 85-115 µs of a 32k mesh's 155-225 µs rebuild.)
  constexpr double kMoveWeight = 0.5;
  block_work_.resize(blocks_);
  for (std::size_t b = 0; b < blocks_; ++b) {
    std::size_t live = 0;
    const std::size_t end = std::min(triangles_, (b + 1) * kTriangleBlock);
    for (std::size_t t = b * kTriangleBlock; t < end; ++t) live += m.triangle_alive[t] != 0 ? 1 : 0;
    block_work_[b] = static_cast<double>(live);
  }
  // (Multiples of 0.5 below 2^52: exact in any grouping, as the additions one at a time were.)
  std::size_t run_block = 0, run = 0;
  for (std::size_t v = 0; v < vertices_; ++v) {
    if (!m.vertex_alive[v]) continue;
    const auto list = adj.of(static_cast<Index>(v));
    if (list.empty()) continue;
    const std::size_t b = static_cast<std::size_t>(list.front()) / kTriangleBlock;
    if (b != run_block) block_work_[run_block] += kMoveWeight * static_cast<double>(run), run_block = b, run = 0;
    ++run;
  }
  if (blocks_ > 0) block_work_[run_block] += kMoveWeight * static_cast<double>(run);
  double total = 0;
  for (double w : block_work_) total += w;
  part_first_block_.assign(parts + 1, blocks_);
  part_first_block_[0] = 0;
  double done = 0;
  std::size_t next = 0;
  for (std::size_t p = 1; p < parts; ++p) {
    // The first block at which the work before it reaches p / parts of the total, leaving
    // every part at least one block.
    const double target = total * static_cast<double>(p) / static_cast<double>(parts);
    while (next < blocks_ - (parts - p) && (done + block_work_[next] <= target || next < part_first_block_[p - 1] + 1))
      done += block_work_[next++];
    part_first_block_[p] = next;
  }
  block_part_.resize(blocks_);
  for (std::size_t p = 0; p < parts; ++p)
    for (std::size_t b = part_first_block_[p]; b < part_first_block_[p + 1]; ++b)
      block_part_[b] = static_cast<std::uint16_t>(p);
  owner_.resize(vertices_);
  last_part_.resize(vertices_);
  group_part_.assign((vertices_ + kGroup - 1) / kGroup, 0);
  // Groups side by side in a parallel cycle (each task writes its own groups' vertices).
  for_range(
      exec, group_part_.size(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t g = begin; g < end; ++g) {
          for (std::size_t v = g * kGroup; v < std::min(vertices_, (g + 1) * kGroup); ++v) refresh_vertex(m, adj, v);
          classify(m, g);
        }
      },
      kUpdateGrain);
  touched_.clear();
  build_buckets();
  // The flags (find_foreign() of every triangle, without testing each): a live triangle's corners
  // are owned by its part or an earlier one (a vertex's first triangle comes no later, and parts
  // are ascending ranges of blocks), so it has a foreign corner iff one of its corners is "split"
  // (its triangles reach beyond its owner part) and it lies beyond that corner's owner part. Split
  // vertices lie in halo groups, a few hundred vertices on the 32k meshes: their lists give every
  // flagged triangle. (Testing every triangle's corners took 44-58 us of a 93-131 us rebuild of
  // the 32k meshes; docs/melt-core.md, issue 20 step 20.)
  foreign_.assign(triangles_, 0);
  block_foreign_.assign(blocks_, 0);
  for (const std::int32_t g : halo_) {
    const std::size_t end = std::min(vertices_, (static_cast<std::size_t>(g) + 1) * kGroup);
    for (std::size_t v = static_cast<std::size_t>(g) * kGroup; v < end; ++v) {
      if (!m.vertex_alive[v]) continue;
      const auto list = adj.of(static_cast<Index>(v));
      if (list.empty()) continue;
      const std::uint16_t own = owner_[v];
      if (part_of_triangle(static_cast<std::size_t>(list.back())) == own) continue;  // not split
      for (const Index t : list) {
        const auto ts = static_cast<std::size_t>(t);
        if (part_of_triangle(ts) == own || foreign_[ts] != 0) continue;
        foreign_[ts] = 1;
        ++block_foreign_[ts / kTriangleBlock];
      }
    }
  }
  valid_ = true;
}

template <class Real>
void DeformSchedule::refresh_vertex(const TriMesh<Real>& m, const VertexTriangles& adj, std::size_t v) {
  owner_[v] = 0, last_part_[v] = kNoTriangles;
  if (!m.vertex_alive[v]) return;
  const auto list = adj.of(static_cast<Index>(v));
  if (list.empty()) return;
  owner_[v] = block_part_[static_cast<std::size_t>(list.front()) / kTriangleBlock];
  last_part_[v] = block_part_[static_cast<std::size_t>(list.back()) / kTriangleBlock];
}

template <class Real>
bool DeformSchedule::classify(const TriMesh<Real>& m, std::size_t g) {
  // A free group (no live vertex with triangles) is interior to part 0, or stays interior to the
  // part it was (its moves change nothing and read no sums, so any one part may make them).
  std::int64_t part = -1;
  bool halo = blocks_ == 0;
  const std::size_t end = std::min(vertices_, (g + 1) * kGroup);
  for (std::size_t v = g * kGroup; v < end; ++v) {
    // (A vertex that died in a merge keeps its parts until it is touched or the schedule rebuilt.)
    if (!m.vertex_alive[v] || last_part_[v] == kNoTriangles) continue;
    const std::uint16_t first = owner_[v];
    if (last_part_[v] != first || (part >= 0 && part != first)) halo = true;
    part = first;
  }
  const std::int32_t before = group_part_[g];
  group_part_[g] = halo ? kHalo : part >= 0 ? static_cast<std::int32_t>(part) : before != kHalo ? before : 0;
  return group_part_[g] != before;
}

void DeformSchedule::build_buckets() {
  // Both passes keep the count (then the write position) of the current run of groups of one
  // part in a register: a part's interior groups come in long runs, and incrementing bucket_ or
  // next_ per group made each increment wait on the store of the one before.
  const std::size_t parts = this->parts();
  bucket_.assign(parts + 1, 0);
  halo_.clear();
  std::int32_t run_part = kHalo, run = 0;
  for (std::size_t g = 0; g < group_part_.size(); ++g) {
    const std::int32_t part = group_part_[g];
    if (part == kHalo) {
      halo_.push_back(static_cast<std::int32_t>(g));
      continue;
    }
    if (part != run_part) {
      if (run_part != kHalo) bucket_[static_cast<std::size_t>(run_part) + 1] += run;
      run_part = part, run = 0;
    }
    ++run;
  }
  if (run_part != kHalo) bucket_[static_cast<std::size_t>(run_part) + 1] += run;
  for (std::size_t p = 0; p < parts; ++p) bucket_[p + 1] += bucket_[p];
  interior_.resize(static_cast<std::size_t>(bucket_[parts]));
  next_.assign(bucket_.begin(), bucket_.end() - 1);
  run_part = kHalo;
  std::int32_t at = 0;
  for (std::size_t g = 0; g < group_part_.size(); ++g) {  // ascending within each part
    const std::int32_t part = group_part_[g];
    if (part == kHalo) continue;
    if (part != run_part) {
      if (run_part != kHalo) next_[static_cast<std::size_t>(run_part)] = at;
      run_part = part, at = next_[static_cast<std::size_t>(part)];
    }
    interior_[static_cast<std::size_t>(at++)] = static_cast<std::int32_t>(g);
  }
}

template void DeformSchedule::update(const TriMesh<float>&, const VertexTriangles&, std::size_t, Execution);
template void DeformSchedule::update(const TriMesh<double>&, const VertexTriangles&, std::size_t, Execution);

}  // namespace meltlab::sim
