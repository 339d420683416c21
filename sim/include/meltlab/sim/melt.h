#pragma once
// The melt/sublimation cycle of the monograph (chapter 3): per cycle
//   Alg. 1  deform       every vertex moves by kg·kl(P)·M, M from M_E and M_N (Eq. 3.6, 3.8)
//   Alg. 2  collapse     edges shorter than kr are collapsed (index-ordering trick, chains)
//   Alg. 3  glued+sort   glued triangle pairs are removed, triangles rotated min-index first
//   repair  (harness)    non-manifold configurations Alg. 2/3 leave behind are resolved
//                        locally: glued pairs the vertex count misses are removed, pinched
//                        vertices split into one vertex per fan (this is how a neck that
//                        collapsed to a point separates the object into parts), and
//                        non-manifold edges are collapsed into such pinches.
//   remnants (harness)   every 16 cycles, parts whose signed volume is <= 0 (flat remnants
//                        that turned inside out) are deleted.
// The deformation and the short-edge test are sweeps over the triangles; everything else
// touches only what changed (vertex -> triangle lists are kept across cycles). The
// short-edge sweep skips triangles that provably cannot have an edge below kr yet (a
// conservative bound on how far vertices have moved), and the arrays are compacted, keeping
// index order, once fewer than half of their slots are live. A cycle therefore costs
// O(live elements), and none of these shortcuts changes the result (tested bitwise against
// the plain algorithms).
//
// Serial and parallel (TBB) execution give bitwise-identical meshes: every floating-point
// sum is taken in the same order (a vertex sums its triangles in ascending triangle index;
// a merge cluster sums its members in ascending vertex index), and every conflict is
// resolved by an order-independent rule (a vertex marked for merging by several triangles
// takes the smallest target). The sources in sim/src/melt/ (deform.cpp, collapse.cpp, glued.cpp,
// repair.cpp, remnants.cpp, compact.cpp, simulator.cpp) give the details and the open choices of §12.

#include <meltlab/sim/kl_field.h>
#include <meltlab/sim/mesh.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace meltlab::sim {

/// Which displacement Alg. 1 uses (the single-vector variants reproduce Figs. 3.1 / 3.4).
enum class DeformMode {
  kCombined,    ///< Eq. 3.6: kE·M_E + kN·M_N where they agree, kN·M_N elsewhere
  kNormalOnly,  ///< M = kN·M_N only (Fig. 3.1: triangles escape after ~1500 cycles)
  kEdgeOnly,    ///< M = kE·M_E only (smooths concavities instead of shrinking, Fig. 3.4)
};

/// The tie N·M_E = 0 (open choice `sign_test_tie`).
enum class TieRule {
  kLessEqual,  ///< Alg. 1: dot(N, M_E) <= 0 takes the combined branch (default)
  kStrict,     ///< Eq. 3.6: only dot(N, M_E) < 0 does
};

/// M_E as the mean of the unit edge vectors (Alg. 1) or their sum (Eq. 3.5, second form).
enum class EdgeSumMode { kMean, kSum };

/// How a merge cluster's position is formed (open choice `merge_position_mode`).
enum class MergeMode {
  kClusterMean,         ///< GPU §5.4: arithmetic mean of the survivor and all vertices merged into it (default)
  kSequentialPairwise,  ///< CPU Alg. 2: survivor absorbs members in ascending order, P_r = (P_k + P_r)/2
};

enum class Execution { kSerial, kParallel };

struct MeltParams {
  double kg = 1.0;  ///< global rate coefficient, in [0, 1] (ambient temperature)
  double kE = 0.0;  ///< weight of M_E, mesh units per cycle (M_E is a mean of unit vectors)
  double kN = 0.0;  ///< weight of M_N, mesh units per cycle; the monograph uses kE ≈ 100 kN
  double kr = 0.0;  ///< minimum edge length, mesh units (Eq. 3.7)
  DeformMode deform = DeformMode::kCombined;
  TieRule tie = TieRule::kLessEqual;
  EdgeSumMode edge_sum = EdgeSumMode::kMean;
  MergeMode merge = MergeMode::kClusterMean;
  bool repair = true;  ///< run the harness's topology repair after Alg. 3
  /// Every K cycles, delete connected parts whose signed volume is <= 0 (0 = never). A flat
  /// remnant whose opposite sides pass through each other turns inside out; its outward
  /// normals then point in, "inward" motion inflates it, and it would grow forever. Such a
  /// part has melted through itself and is removed.
  int remnant_check_every = 16;
  /// Compact the arrays (dead slots dropped, relative order of indices kept) when fewer than
  /// this fraction of the triangle slots is live; 0 = never, as in the monograph (§3.5: flags
  /// only, fixed length). Keeping the order keeps every "smaller index wins" decision of
  /// Alg. 2 the same, so the melt is identical; only indices shift and sweeps get shorter.
  double compact_below = 0.5;
  /// Also compact once the dead slots have cost about what a compaction costs: when the dead
  /// fraction of the triangle slots, summed over the cycles since the last compaction, reaches
  /// this (0 = by compact_below only). Every sweep of a cycle pays for a dead slot about as for
  /// a live one, and a compaction costs about one cycle (docs/melt-core.md, issue 20 step 13),
  /// so at 1 the compactions cost at most about what the dead slots did (the ski-rental
  /// rule). Counts only, no clocks: the same cycles compact in every run.
  double compact_after = 1.0;

  /// Throws InputError naming the parameter if a value is not finite or out of range.
  void validate() const;
};

/// Coefficients relative to a mesh's size, as the CLI's default `--units relative` uses
/// them: kE = ke_rel·L0 and kr = kr_rel·L0 with L0 the mean edge length, kN = kE/100 (the
/// monograph's kE ≈ 100 kN). The defaults are the CLI's defaults.
MeltParams relative_melt_params(const IndexedMesh& mesh, double ke_rel = 0.05, double kr_rel = 0.5, double kg = 1.0);

/// What one cycle did.
struct CycleReport {
  std::int64_t merged_vertices = 0;         ///< Alg. 2: vertices merged into another
  std::int64_t degenerate_triangles = 0;    ///< Alg. 2: triangles deleted for a repeated index
  std::int64_t glued_triangles = 0;         ///< Alg. 3: triangles on a vertex with count 2
  std::int64_t glued_vertices = 0;          ///< Alg. 3: vertices with count 2
  std::int64_t orphan_vertices = 0;         ///< vertices left without triangles, deleted
  std::int64_t repair_glued_pairs = 0;      ///< repair: glued pairs Alg. 3's count test missed
  std::int64_t repair_edge_collapses = 0;   ///< repair: non-manifold edges collapsed
  std::int64_t repair_vertex_splits = 0;    ///< repair: extra vertices created by splitting pinches
  std::int64_t inverted_parts_removed = 0;  ///< parts with volume <= 0 deleted (remnant check)
  std::int64_t live_vertices = 0;           ///< after the cycle
  std::int64_t live_triangles = 0;          ///< after the cycle
  /// Wall time of each pass, milliseconds: Alg. 1, Alg. 2, Alg. 3, repair, and the remnant
  /// check (0 in the cycles without one).
  double deform_ms = 0, collapse_ms = 0, glued_ms = 0, repair_ms = 0, remnant_ms = 0;
  double compact_ms = 0;   ///< the compaction's wall time (0 in the cycles without one)
  bool compacted = false;  ///< the arrays were compacted at the end of this cycle
  bool topology_changed() const {
    return repair_vertex_splits > 0 || repair_edge_collapses > 0 || repair_glued_pairs > 0 ||
           inverted_parts_removed > 0;
  }
};

struct MeltWorkspace;  // scratch arrays kept across cycles (defined in sim/src/melt/workspace.h)

/// Runs the melt cycle on a mesh it owns. Keeps its scratch buffers across cycles, so a
/// cycle allocates nothing once the arrays have grown to size.
template <class Real>
class MeltSimulator {
 public:
  /// `mesh` must be a valid closed solid (see check_topology); its triangles are sorted
  /// min-index first here (the "once" step before the first cycle, §3.6).
  MeltSimulator(TriMesh<Real> mesh, MeltParams params, KlFieldPtr kl, Execution exec = Execution::kSerial);
  ~MeltSimulator();
  MeltSimulator(MeltSimulator&&) noexcept;
  MeltSimulator& operator=(MeltSimulator&&) noexcept;

  /// One cycle: Alg. 1, Alg. 2, Alg. 3, repair.
  CycleReport step();

  const TriMesh<Real>& mesh() const { return mesh_; }
  const MeltParams& params() const { return params_; }
  void set_params(const MeltParams& p);
  Execution execution() const { return exec_; }
  void set_execution(Execution e) { exec_ = e; }
  /// Parts the deformation sweep is split into (0, the default: one per thread TBB may use,
  /// 1 for a serial cycle or a small mesh). Any count gives bitwise the same mesh; tests set
  /// it to exercise partitions (halo vertices) independently of the thread count.
  void set_sweep_parts(std::size_t parts);
  /// Whether Alg. 1 writes the mesh's N and M columns (vertex normal, last move) and Nf (face
  /// normal). Off by default: no pass of the cycle reads them back (each computes what it
  /// needs in registers), and their stores cost 6-9 % of a serial 32k cycle (docs/melt-core.md,
  /// issue 20 step 7); the columns then keep the values they had. Turn it on to inspect them
  /// after step(): positions and topology are bitwise the same either way.
  void set_record_vectors(bool on);
  bool record_vectors() const;
  std::int64_t cycle() const { return cycle_; }
  bool empty() const;  ///< true once every triangle has melted away

 private:
  TriMesh<Real> mesh_;
  MeltParams params_;
  KlFieldPtr kl_;
  Execution exec_;
  std::int64_t cycle_ = 0;
  double dead_share_sum_ = 0;  ///< dead fraction of the triangle slots summed since the last compaction
  std::unique_ptr<MeltWorkspace> ws_;
};

// ---- the individual algorithms, for tests and for callers that compose their own cycle ----

/// Alg. 1 on all live vertices: face normals, vertex normals, M_E, and the move (all written
/// to the mesh's columns, unlike MeltSimulator's cycle by default).
template <class Real>
void deform(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec = Execution::kSerial);

/// Alg. 2: collapses edges shorter than kr. Returns the vertices merged and the triangles
/// deleted as degenerate. Precondition: triangles sorted min-index first.
template <class Real>
CycleReport collapse_short_edges(TriMesh<Real>& m, double kr, MergeMode merge, Execution exec = Execution::kSerial);

/// Alg. 2's chain flattening: given merge targets with target[k] <= k (k merges into
/// target[k]; target[k] == k for none), returns the end of every chain (Fig. 3.11).
/// Throws InvariantError if some target[k] > k.
std::vector<Index> flatten_merge_targets(const std::vector<Index>& target);

/// Alg. 3: rotates triangles min-index first, removes glued triangle pairs (vertex
/// triangle count 2) and deletes vertices left with count 2 or 0.
template <class Real>
CycleReport remove_glued_and_sort(TriMesh<Real>& m, Execution exec = Execution::kSerial);

/// The harness's local topology repair over the given vertices (see the header comment).
/// Returns what it did. Throws InvariantError if it cannot converge (never observed; a bug).
template <class Real>
CycleReport repair_topology(TriMesh<Real>& m, const std::vector<Index>& vertices);

/// Deletes every connected part of the live mesh whose signed volume is <= 0 (see
/// MeltParams::remnant_check_every). Returns the number of parts removed. O(n). In parallel the
/// union-find over the triangles runs in chunks side by side; the parts are the same.
template <class Real>
std::int64_t remove_inverted_parts(TriMesh<Real>& m, Execution exec = Execution::kSerial);

/// Drops dead slots from every array, keeping the relative order of the live vertices and
/// triangles (so Alg. 2's index comparisons are unchanged). Returns, for every old vertex
/// slot, its new index (-1 if dead). In place: the arrays keep their capacity. In parallel the
/// arrays are compacted side by side; the result is the same.
template <class Real>
std::vector<Index> compact_mesh(TriMesh<Real>& m, Execution exec = Execution::kSerial);

/// Rotates every live triangle min-index first (Alg. 3's sort step alone).
template <class Real>
void sort_triangle_indices(TriMesh<Real>& m);

}  // namespace meltlab::sim
