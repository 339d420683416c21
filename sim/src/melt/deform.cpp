// Alg. 1: mesh deformation (monograph §3.1–3.4, Eq. 2.9, 2.10, 3.1–3.8).
//
// Every triangle contributes its unit face normal (Eq. 2.9) and, at each corner, the unit
// edge vector to the next corner; every vertex sums them, normalises N (Eq. 2.10), takes
// the mean M_E (Eq. 3.5) and moves by kg·kl(P)·M (Eq. 3.6, 3.8).
//
// Blocks of triangles in ascending order gather their corners from a packed (x, y, z, 0)
// copy of the positions (workspace.h), compute their terms and add each corner's terms to
// the corner's sum record (one SIMD addition); groups of eight vertex slots move eight
// vertices at a time in SIMD lanes (lanes.h), each lane with the scalar formulas'
// operations in their order, read the old positions from the packed copy and write the new
// ones to it and to the columns; each group clears the records it read as it moves (zero
// for the next cycle). A one-part (serial) sweep adds all triangles and then moves every
// group in ascending order. A sweep in parts (deform_schedule.h) runs parts of the blocks
// side by side; each part adds its triangles into the records of the vertices it
// owns and then moves the groups interior to it; vertices with triangles in later parts
// add those triangles' stored terms afterwards, in the same ascending triangle order as the
// serial sweep adds them, and the groups not interior to one part move then. Every vertex
// therefore adds the same numbers in the same order whatever the execution:
// bitwise-identical meshes (with -ffp-contract=off, see cmake/flags.cmake). A vertex's
// triangle count is the length of its list.

#include "deform_schedule.h"
#include "triangle_kernels.h"
#include "workspace.h"

#include <meltlab/core/error.h>

#include <tbb/global_control.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <cstring>
#include <span>
#include <stdexcept>
#include <type_traits>

namespace meltlab::sim {

namespace {

// The constants of the vertex moves.
template <class Real>
struct MoveConstants {
  Real kE, kN;
  bool mean, less_equal;
};

// Lanes of eight vertex slots: the inputs and outputs of move_group().
template <class Real>
struct VertexGroup {
  VertexSums<Real>* sums;  // 8 records, read (and cleared for the next cycle if `clear_sums`)
  bool clear_sums;
  const Index* count;  // triangles per vertex
  const std::uint8_t* alive;
  Real *px, *py, *pz;     // out: positions, 8 per column
  bool record;            // write the normals and displacements (MeltWorkspace::record_vectors)
  Real *nx, *ny, *nz;     // out: normals
  Real *mx, *my, *mz;     // out: displacements
  Index* triangle_count;  // out
  Real* packed;           // positions as 8 packed triples (in and out)
};

// Moves eight vertices (Eq. 2.10, 3.5, 3.6, 3.8) with lane arithmetic: every lane runs the
// operations of the three-component formulas in their order (dot products summed left to
// right, as in the triangle kernel), so results do not depend on how vertices are grouped. `s` is kg·kl per lane.
// A live vertex without triangles (orphan_vertex_policy: deleted by Alg. 3) and a dead slot
// do not move and get N = M = 0 (and t = 0 for a dead slot). Updates the lane maxima of |move|
// and |P| over the moved vertices.
// Inlined into the loops over groups (with move_group_at): GCC 12 kept both as calls, which built the
// group's sixteen pointers on the stack per group of eight vertices; inlined, the serial 32k cycles
// ran 4-8 % faster (docs/melt-core.md, issue 20 step 19).
template <class Real, DeformMode kMode>
[[gnu::always_inline]] inline void move_group(const MoveConstants<Real>& c, const VertexGroup<Real>& g,
                                              const Lanes<Real>& s, Lanes<Real>& max_move, Lanes<Real>& max_coord) {
  using L = Lanes<Real>;
  using Mask = LaneMask<Real>;
  L rec[kLanes], col[kLanes];
  for (std::size_t i = 0; i < kLanes; ++i) rec[i] = g.sums[i].lane;
  if (g.clear_sums)
    for (std::size_t i = 0; i < kLanes; ++i) g.sums[i].lane = L{};
  transpose8<Real>(rec, col);
  const L count = lanes_from_ints<Real>(g.count);  // 8 triangle counts
  const Mask live = lanes_nonzero<Real>(g.alive);  // 8 flags, widened in registers
  const Mask has = live & (count > Real(0));       // live with triangles: moves

  const L n2 = col[0] * col[0] + col[1] * col[1] + col[2] * col[2];
  const L inv = lane_inverse_length<Real>(n2);  // Eq. 2.10
  const L Nx = col[0] * inv, Ny = col[1] * inv, Nz = col[2] * inv;
  L MEx = col[3], MEy = col[4], MEz = col[5];  // Eq. 3.5: sum, or mean
  if (c.mean) {
    const L divisor = lane_select<Real>(has, count, broadcast<Real>(1));
    MEx = MEx / divisor, MEy = MEy / divisor, MEz = MEz / divisor;
  }
  L mx, my, mz;
  if constexpr (kMode == DeformMode::kCombined) {
    // M_N = -N, so Eq. 3.6's agreement test M_N·M_E > 0 is N·M_E < 0 (Alg. 1: <=).
    const L d = Nx * MEx + Ny * MEy + Nz * MEz;
    const Mask combined = c.less_equal ? d <= Real(0) : d < Real(0);
    const Real mkN = -c.kN;
    mx = lane_select<Real>(combined, (c.kE * MEx - c.kN * Nx) * s, (mkN * Nx) * s);
    my = lane_select<Real>(combined, (c.kE * MEy - c.kN * Ny) * s, (mkN * Ny) * s);
    mz = lane_select<Real>(combined, (c.kE * MEz - c.kN * Nz) * s, (mkN * Nz) * s);
  } else if constexpr (kMode == DeformMode::kNormalOnly) {
    const Real mkN = -c.kN;
    mx = (mkN * Nx) * s, my = (mkN * Ny) * s, mz = (mkN * Nz) * s;
  } else {
    mx = (c.kE * MEx) * s, my = (c.kE * MEy) * s, mz = (c.kE * MEz) * s;
  }
  const L zero{};
  mx = lane_select<Real>(has, mx, zero), my = lane_select<Real>(has, my, zero);
  mz = lane_select<Real>(has, mz, zero);
  L px, py, pz;
  deinterleave3<Real>(g.packed, px, py, pz);
  px = lane_select<Real>(has, px + mx, px);  // Eq. 3.8
  py = lane_select<Real>(has, py + my, py), pz = lane_select<Real>(has, pz + mz, pz);
  store_lanes<Real>(g.px, px), store_lanes<Real>(g.py, py), store_lanes<Real>(g.pz, pz);
  interleave3<Real>(g.packed, px, py, pz);
  if (g.record) {
    store_lanes<Real>(g.nx, lane_select<Real>(has, Nx, zero));
    store_lanes<Real>(g.ny, lane_select<Real>(has, Ny, zero));
    store_lanes<Real>(g.nz, lane_select<Real>(has, Nz, zero));
    store_lanes<Real>(g.mx, mx), store_lanes<Real>(g.my, my), store_lanes<Real>(g.mz, mz);
  }
  for (std::size_t i = 0; i < kLanes; ++i) g.triangle_count[i] = g.alive[i] ? g.count[i] : 0;
  max_move = lane_max<Real>(max_move,
                            lane_max<Real>(lane_max<Real>(lane_abs<Real>(mx), lane_abs<Real>(my)), lane_abs<Real>(mz)));
  const L coord = lane_max<Real>(lane_max<Real>(lane_abs<Real>(px), lane_abs<Real>(py)), lane_abs<Real>(pz));
  max_coord = lane_max<Real>(max_coord, lane_select<Real>(has, coord, zero));
}

// What the sweep of one cycle shares between its parts.
template <class Real, class ScaleAt>
struct Sweep {
  TriMesh<Real>& m;
  MoveConstants<Real> c;
  VertexSums<Real>* sums;
  bool record;          // write N, M and Nf (MeltWorkspace::record_vectors)
  const Index* counts;  // triangles per vertex (the list lengths)
  const VertexTriangles& adj;
  const DeformSchedule& plan;
  Real* packed;                       // positions as packed triples: gathered, then written by the moves
  TriangleTerms<Real>* stored_terms;  // terms of triangles with a corner owned by an earlier part
  float* min_edge2;                   // out: shortest squared edge per triangle slot (+inf: dead)
  const ScaleAt& scale_at;            // kg·kl: a number, or a function of the vertex slot
};

// Halo groups a task claims at a time in the halo phase of a parallel sweep (each gathers stored
// terms and moves eight vertices; the geodesic 32k in its generated order has 209 halo groups).
constexpr std::size_t kHaloGrain = 32;

// Per-thread maxima of |move| and |P| (lanes), for the short-edge skip bound.
template <class Real>
struct MoveMaxima {
  Lanes<Real> move{}, coord{};
};

// Moves group g (vertex slots [8g, 8g + 8), the last group through padded copies so that
// every vertex runs the same code).
template <class Real, DeformMode kMode, class ScaleAt>
[[gnu::always_inline]] inline void move_group_at(const Sweep<Real, ScaleAt>& w, std::size_t g, MoveMaxima<Real>& mx) {
  TriMesh<Real>& m = w.m;
  auto scale = [&](std::size_t v, const Index* count, const std::uint8_t* alive) {
    if constexpr (std::is_arithmetic_v<ScaleAt>) {
      return broadcast<Real>(w.scale_at);
    } else {
      Lanes<Real> s{};
      for (std::size_t i = 0; i < kLanes; ++i)
        if (alive[i] && count[i] > 0) s[i] = w.scale_at(v + i);
      return s;
    }
  };
  Real* const P[3] = {m.position.x().data(), m.position.y().data(), m.position.z().data()};
  Real* const N[3] = {m.normal.x().data(), m.normal.y().data(), m.normal.z().data()};
  Real* const D[3] = {m.displacement.x().data(), m.displacement.y().data(), m.displacement.z().data()};
  const std::size_t v = g * kLanes;
  const std::size_t n = std::min(kLanes, m.vertex_slots() - v);
  if (n == kLanes) {
    const VertexGroup<Real> grp{&w.sums[v],      true,     &w.counts[v], &m.vertex_alive[v], P[0] + v,
                                P[1] + v,        P[2] + v, w.record,     N[0] + v,           N[1] + v,
                                N[2] + v,        D[0] + v, D[1] + v,     D[2] + v,           &m.triangle_count[v],
                                w.packed + 3 * v};
    move_group<Real, kMode>(w.c, grp, scale(v, grp.count, grp.alive), mx.move, mx.coord);
    return;
  }
  VertexSums<Real> pad_sums[kLanes] = {};
  Index pad_count[kLanes] = {}, pad_tcount[kLanes] = {};
  std::uint8_t pad_alive[kLanes] = {};
  Real pad_p[3][kLanes], pad_n[3][kLanes], pad_d[3][kLanes];
  Real pad_packed[3 * kLanes] = {};
  std::copy_n(&w.sums[v], n, pad_sums);
  std::fill_n(&w.sums[v], n, VertexSums<Real>{});
  std::copy_n(&w.counts[v], n, pad_count);
  std::copy_n(&m.vertex_alive[v], n, pad_alive);
  std::copy_n(w.packed + 3 * v, 3 * n, pad_packed);
  move_group<Real, kMode>(w.c,
                          {pad_sums, false, pad_count, pad_alive, pad_p[0], pad_p[1], pad_p[2], true, pad_n[0],
                           pad_n[1], pad_n[2], pad_d[0], pad_d[1], pad_d[2], pad_tcount, pad_packed},
                          scale(v, pad_count, pad_alive), mx.move, mx.coord);
  for (int a = 0; a < 3; ++a) {
    std::copy_n(pad_p[a], n, P[a] + v);
    if (w.record) {
      std::copy_n(pad_n[a], n, N[a] + v);
      std::copy_n(pad_d[a], n, D[a] + v);
    }
  }
  std::copy_n(pad_tcount, n, &m.triangle_count[v]);
  std::copy_n(pad_packed, 3 * n, w.packed + 3 * v);
}

// The additions of a block's triangles [from, to) (whole groups of eight) into their corners'
// records: each group's 3 x 8 corner records (n, e_k, 0, 0) come from three 8 x 8 transposes of the
// block's term arrays in registers and are added in triangle order, corner by corner (the additions
// and their order of the loop in sweep_block(), so the same bits). That loop builds each record from
// six scalars with inserts; this cut the serial float cycle to 0.82-0.85 on the 32k meshes (0.87 on
// the bunny, 0.94 on the dragon; issue 20 step 23), and the double one to 0.97-0.98 once transpose8
// was inlined (step 24; out of line it had been 1.03-1.07x slower in double). Not inlined here:
// inlined into sweep_block() the 24 records competed for registers and the serial float cycle lost
// 11 % (docs/melt-core.md, issue 20 steps 23-24).
template <class Real, class ScaleAt>
[[gnu::noinline]] void add_groups_transposed(const Sweep<Real, ScaleAt>& w, const TriangleBlockTerms<Real>& terms,
                                             std::size_t first, std::size_t from, std::size_t to) {
  using L = Lanes<Real>;
  const std::uint8_t* const alive = w.m.triangle_alive.data();
  const Triangle* const triangles = w.m.triangle.data();
  for (std::size_t i0 = from; i0 < to; i0 += kLanes) {
    L rec[3][kLanes];
    const L nx = load_lanes<Real>(terms.nx + i0), ny = load_lanes<Real>(terms.ny + i0);
    const L nz = load_lanes<Real>(terms.nz + i0);
    for (std::size_t k = 0; k < 3; ++k) {
      const L in[kLanes] = {nx,
                            ny,
                            nz,
                            load_lanes<Real>(terms.ex[k] + i0),
                            load_lanes<Real>(terms.ey[k] + i0),
                            load_lanes<Real>(terms.ez[k] + i0),
                            L{},
                            L{}};
      transpose8<Real>(in, rec[k]);
    }
    for (std::size_t j = 0; j < kLanes; ++j) {
      const std::size_t t = first + i0 + j;
      if (!alive[t]) continue;
      const Triangle& tri = triangles[t];
      for (std::size_t k = 0; k < 3; ++k) w.sums[static_cast<std::size_t>(tri[k])].lane += rec[k][j];
    }
  }
}

// Block b of the sweep, in part `part`: its triangles' terms and face normals, and the
// additions into the sums of the corners the part owns; a triangle with a corner owned by an
// earlier part stores its terms for the halo phase (kHalo: the sweep is in parts).
template <bool kHalo, class Real, class ScaleAt>
void sweep_block(const Sweep<Real, ScaleAt>& w, std::size_t b, std::size_t part, TriangleBlockTerms<Real>& terms) {
  TriMesh<Real>& m = w.m;
  const std::size_t first = b * kTriangleBlock;
  const std::size_t count = std::min(kTriangleBlock, m.triangle_slots() - first);
  triangle_block_terms(m, w.packed, first, count, terms);
  Real* const FN[3] = {m.face_normal.x().data(), m.face_normal.y().data(), m.face_normal.z().data()};
  const std::uint8_t* const alive = m.triangle_alive.data();
  if (w.record)
    for (std::size_t i = 0; i < count; ++i) {  // dead slots keep their face normal
      FN[0][first + i] = alive[first + i] ? terms.nx[i] : FN[0][first + i];
      FN[1][first + i] = alive[first + i] ? terms.ny[i] : FN[1][first + i];
      FN[2][first + i] = alive[first + i] ? terms.nz[i] : FN[2][first + i];
    }
  std::memcpy(w.min_edge2 + first, terms.min_edge2, count * sizeof(float));
  const std::uint16_t* const owner = w.plan.owners();
  // kTest: some corner may be owned by another part (DeformSchedule::block_mixed); then the
  // triangles flagged foreign test the owner of each corner (a mixed block of the geodesic 32k's
  // generated order holds about five of them in 64; testing every triangle cost 2-4 % of a
  // two-thread cycle there, docs/melt-core.md, issue 20 step 20).
  const std::uint8_t* const foreign = w.plan.foreign();
  auto add = [&](auto test_c, std::size_t from, std::size_t to) {
    constexpr bool kTest = decltype(test_c)::value;
    for (std::size_t i = from; i < to; ++i) {
      const std::size_t t = first + i;
      if (!alive[t]) continue;
      const Triangle& tri = m.triangle[t];
      const bool test = kTest && foreign[t] != 0;
      bool store = false;
      for (std::size_t k = 0; k < 3; ++k) {
        if (test && owner[static_cast<std::size_t>(tri[k])] != part) {
          store = true;
          continue;
        }
        w.sums[static_cast<std::size_t>(tri[k])].lane +=
            Lanes<Real>{terms.nx[i], terms.ny[i], terms.nz[i], terms.ex[k][i], terms.ey[k][i], terms.ez[k][i], 0, 0};
      }
      if (test && store) {
        TriangleTerms<Real>& out = w.stored_terms[t];
        out.normal = Vec3<Real>(terms.nx[i], terms.ny[i], terms.nz[i]);
        for (std::size_t k = 0; k < 3; ++k) out.edge[k] = Vec3<Real>(terms.ex[k][i], terms.ey[k][i], terms.ez[k][i]);
      }
    }
  };
  const bool mixed = kHalo && w.plan.block_mixed(b);
  // Whole groups of eight by transposes, in runs of groups without a triangle flagged foreign (all
  // of them unless the block is mixed); a group with one takes the loop with the owner tests. Where
  // eight doubles are two AVX registers (no AVX-512) the transposes measured 1.35-1.46x slower than
  // the loop, which then takes every triangle (docs/melt-core.md, issue 20 step 24).
  std::size_t grouped = 0;
  if constexpr (!std::is_class_v<Lanes<Real>>) {
    auto flagged = [&](std::size_t i0) {
      if (!mixed) return false;
      std::uint64_t flags;
      std::memcpy(&flags, foreign + first + i0, sizeof(flags));
      return flags != 0;
    };
    grouped = count / kLanes * kLanes;
    std::size_t i0 = 0;
    while (i0 < grouped) {
      if (flagged(i0)) {
        add(std::true_type{}, i0, i0 + kLanes);
        i0 += kLanes;
        continue;
      }
      std::size_t run_end = i0 + kLanes;
      while (run_end < grouped && !flagged(run_end)) run_end += kLanes;
      add_groups_transposed(w, terms, first, i0, run_end);
      i0 = run_end;
    }
  }
  if (mixed)  // the rest (a block's last triangles that do not fill a group)
    add(std::true_type{}, grouped, count);
  else
    add(std::false_type{}, grouped, count);
}

// Part p of the sweep: its blocks in ascending order, then its interior groups in ascending
// order (the vertex arrays stream; moving each group right after the block that completes its
// sums measured 1.5x slower on the 871k dragon, see docs/melt-core.md, issue 20 step 6).
template <bool kHalo, DeformMode kMode, class Real, class ScaleAt>
void sweep_part(const Sweep<Real, ScaleAt>& w, std::size_t p, MoveMaxima<Real>& mx) {
  TriangleBlockTerms<Real> terms;
  for (std::size_t b = w.plan.part_first_block(p); b < w.plan.part_first_block(p + 1); ++b)
    sweep_block<kHalo>(w, b, p, terms);
  for (std::int32_t g : w.plan.interior_groups(p)) move_group_at<Real, kMode>(w, static_cast<std::size_t>(g), mx);
}

// A halo group: each split vertex (triangles beyond its owner part) adds the stored terms of
// those triangles to the sums its owner part added, in ascending order (the additions of the
// serial sweep), then the group moves.
template <DeformMode kMode, class Real, class ScaleAt>
void halo_group(const Sweep<Real, ScaleAt>& w, std::size_t g, MoveMaxima<Real>& mx) {
  const TriMesh<Real>& m = w.m;
  const DeformSchedule& plan = w.plan;
  const std::size_t end = std::min(m.vertex_slots(), (g + 1) * kLanes);
  for (std::size_t v = g * kLanes; v < end; ++v) {
    if (!m.vertex_alive[v]) continue;
    const auto list = w.adj.of(static_cast<Index>(v));
    if (list.empty()) continue;
    const std::size_t own = plan.owner(static_cast<Index>(v));
    if (plan.part_of_triangle(static_cast<std::size_t>(list.back())) == own) continue;
    Lanes<Real>& sums = w.sums[v].lane;
    for (Index t : list) {
      const auto ts = static_cast<std::size_t>(t);
      if (plan.part_of_triangle(ts) == own) continue;  // added by the owner part
      const TriangleTerms<Real>& terms = w.stored_terms[ts];
      const Vec3<Real>& e = terms.edge[corner_of(m.triangle[ts], static_cast<Index>(v))];
      sums += Lanes<Real>{terms.normal.x(), terms.normal.y(), terms.normal.z(), e.x(), e.y(), e.z(), 0, 0};
    }
  }
  move_group_at<Real, kMode>(w, g, mx);
}

// The sweep of one cycle; returns a bound on how far any vertex moved: the largest |move|
// plus the rounding of P + move (half an ulp of the largest coordinate per component).
template <DeformMode kMode, class Real, class ScaleAt>
double sweep(const Sweep<Real, ScaleAt>& w, std::size_t parts, Execution exec) {
  std::atomic<double> max_move{0.0}, max_coord{0.0};
  auto publish = [&](const MoveMaxima<Real>& mx) {
    Real local_move = 0, local_coord = 0;
    for (std::size_t i = 0; i < kLanes; ++i) {
      local_move = std::max(local_move, mx.move[i]);
      local_coord = std::max(local_coord, mx.coord[i]);
    }
    auto atomic_max = [](std::atomic<double>& a, double x) {
      double cur = a.load(std::memory_order_relaxed);
      while (x > cur && !a.compare_exchange_weak(cur, x, std::memory_order_relaxed)) {
      }
    };
    atomic_max(max_move, static_cast<double>(local_move));
    atomic_max(max_coord, static_cast<double>(local_coord));
  };
  const DeformSchedule& plan = w.plan;
  if (parts == 1) {
    // One part: every triangle adds into its corners' records, then every group moves, in
    // ascending order (the vertex arrays stream through the cache once, which measured faster
    // than moving each group right after its last triangle; the corners were gathered from
    // the packed copy of the old positions, so the order of the moves does not matter).
    MoveMaxima<Real> mx;
    TriangleBlockTerms<Real> terms;
    const std::size_t blocks = (w.m.triangle_slots() + kTriangleBlock - 1) / kTriangleBlock;
    for (std::size_t b = 0; b < blocks; ++b) sweep_block<false>(w, b, 0, terms);
    const std::size_t groups = (w.m.vertex_slots() + kGroup - 1) / kGroup;
    for (std::size_t g = 0; g < groups; ++g) move_group_at<Real, kMode>(w, g, mx);
    publish(mx);
  } else {
    // The parts and then the halo groups in one region of tasks (one per part), each claiming work:
    // a part at a time, then, once every part has finished, kHaloGrain halo groups at a time. A task
    // waits for parts only when all are claimed, so by tasks that run: no task waits on work nobody
    // has taken (if TBB runs fewer tasks at once, one does all, as the serial sweep's one call does).
    // Two regions (the parts, then the halo groups) cost a worker's second wake-up and join.
    const auto halo = plan.halo_groups();
    const std::size_t nparts = plan.parts();
    std::atomic<std::size_t> next_part{0}, parts_done{0}, next_halo{0};
    auto run = [&](std::size_t) {
      MoveMaxima<Real> mx;
      for (std::size_t p; (p = next_part.fetch_add(1, std::memory_order_relaxed)) < nparts;) {
        sweep_part<true, kMode>(w, p, mx);
        parts_done.fetch_add(1, std::memory_order_release);
      }
      while (parts_done.load(std::memory_order_acquire) < nparts) _mm_pause();
      for (std::size_t i; (i = next_halo.fetch_add(kHaloGrain, std::memory_order_relaxed)) < halo.size();) {
        const std::size_t end = std::min(halo.size(), i + kHaloGrain);
        for (; i < end; ++i) halo_group<kMode>(w, static_cast<std::size_t>(halo[i]), mx);
      }
      publish(mx);
    };
    if (exec == Execution::kSerial)
      run(0);
    else
      tbb::parallel_for(std::size_t{0}, nparts, run, tbb::simple_partitioner());
  }
  // |move| <= sqrt(3) * max component; rounding of each component <= eps * |coordinate|.
  constexpr double kSqrt3 = 1.7320508075688772;
  return kSqrt3 * (max_move.load() + static_cast<double>(std::numeric_limits<Real>::epsilon()) * max_coord.load());
}

template <class Real, class ScaleAt>
double sweep(const Sweep<Real, ScaleAt>& w, DeformMode mode, std::size_t parts, Execution exec) {
  switch (mode) {
    case DeformMode::kCombined:
      return sweep<DeformMode::kCombined>(w, parts, exec);
    case DeformMode::kNormalOnly:
      return sweep<DeformMode::kNormalOnly>(w, parts, exec);
    case DeformMode::kEdgeOnly:
      return sweep<DeformMode::kEdgeOnly>(w, parts, exec);
  }
  throw std::logic_error("deform: unknown DeformMode");
}

// Parts of a parallel sweep: one per thread TBB may use (1 for a serial sweep or a mesh too
// small to split), unless the workspace asks for a number.
std::size_t sweep_parts(Execution exec, std::size_t triangles, std::size_t requested) {
  if (requested > 0) return requested;
  if (exec == Execution::kSerial || triangles < 2 * kParallelGrain) return 1;
  const std::size_t threads = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  return std::max<std::size_t>(1, std::min(threads, triangles / kParallelGrain));
}

}  // namespace

template <class Real>
void deform_pass(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec, MeltWorkspace& ws) {
  prepare_workspace(ws, m);
  // One part needs no schedule (see sweep()); it is rebuilt when parts are asked for again.
  const std::size_t parts = sweep_parts(exec, m.triangle_slots(), ws.deform_parts);
  if (parts == 1)
    ws.schedule.invalidate();
  else
    ws.schedule.update(m, ws.adj, parts, exec);
  // The sums start at zero: every group's move clears the records it read, so they are zero at
  // the next cycle (new slots are zero; the first cycle clears them all). One memset before a
  // one-part sweep instead measured 1.01-1.07x slower on every mesh, serial, in both precisions
  // (docs/melt-core.md, issue 20 step 22).
  std::vector<VertexSums<Real>>& sums = ws.vertex_sums<Real>();
  if (!ws.sums_zero)
    sums.assign(m.vertex_slots(), VertexSums<Real>{});
  else
    sums.resize(m.vertex_slots());
  ws.sums_zero = false;  // true again once the sweep has moved (and so cleared) every group
  StoredTerms<Real>& stored = ws.triangle_terms<Real>();
  if (parts > 1 && !ws.schedule.halo_groups().empty()) stored.ensure(m.triangle_slots());
  const MoveConstants<Real> c{static_cast<Real>(p.kE), static_cast<Real>(p.kN), p.edge_sum == EdgeSumMode::kMean,
                              p.tie == TieRule::kLessEqual};
  const Index* counts = ws.adj.counts().data();
  std::vector<Real>& packed = ws.packed_positions<Real>();
  if (!ws.packed_valid || packed.size() != 3 * m.vertex_slots() + 1) pack_positions(m, packed);
  ws.packed_valid = true;  // the moves keep it up to date
  std::vector<float>& min_edge2 = ws.min_edge2;
  min_edge2.resize(m.triangle_slots());  // every slot is written by the sweep
  ws.min_edge2_current = true;
  // A constant kl costs nothing per vertex: s = kg·kl is folded into one number.
  if (kl.is_constant()) {
    const auto s = static_cast<Real>(p.kg * kl.value(Vec3<double>::Zero()));
    const Sweep<Real, Real> w{m,      c,           sums.data(),   ws.record_vectors, counts,
                              ws.adj, ws.schedule, packed.data(), stored.slot.get(), min_edge2.data(),
                              s};
    ws.cycle_move_bound = sweep(w, p.deform, parts, exec);
  } else {
    auto scale_at = [&](std::size_t v) {
      return static_cast<Real>(p.kg * kl.value(m.position[v].template cast<double>()));
    };
    const Sweep<Real, decltype(scale_at)> w{m,       c,           sums.data(),   ws.record_vectors, counts,
                                            ws.adj,  ws.schedule, packed.data(), stored.slot.get(), min_edge2.data(),
                                            scale_at};
    ws.cycle_move_bound = sweep(w, p.deform, parts, exec);
  }
  ws.sums_zero = true;
}

template <class Real>
void deform(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec) {
  p.validate();
  MeltWorkspace ws;
  deform_pass(m, p, kl, exec, ws);
}

template void deform_pass(TriMesh<float>&, const MeltParams&, const KlField&, Execution, MeltWorkspace&);
template void deform_pass(TriMesh<double>&, const MeltParams&, const KlField&, Execution, MeltWorkspace&);
template void deform(TriMesh<float>&, const MeltParams&, const KlField&, Execution);
template void deform(TriMesh<double>&, const MeltParams&, const KlField&, Execution);

}  // namespace meltlab::sim
