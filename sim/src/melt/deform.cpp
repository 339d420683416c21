// Alg. 1: mesh deformation (monograph §3.1–3.4, Eq. 2.9, 2.10, 3.1–3.8).
//
// Every triangle contributes its unit face normal (Eq. 2.9) and, at each corner, the unit
// edge vector to the next corner; every vertex sums them, normalises N (Eq. 2.10), takes
// the mean M_E (Eq. 3.5) and moves by kg·kl(P)·M (Eq. 3.6, 3.8).
// Serial: one sweep over the triangles scatters into the corners' sum records (sequential
// reads of the triangle array, one SIMD addition per corner). Parallel: triangles compute
// their terms, then each vertex gathers from its triangle list. Lists are kept in ascending
// triangle order, so every vertex adds the same numbers in the same order in both modes:
// bitwise-identical meshes (with -ffp-contract=off, see cmake/flags.cmake). A vertex's
// triangle count is the length of its list. The vertex moves then run eight vertices at a
// time in SIMD lanes (lanes.h), each lane with the scalar formulas' operations in their order.

#include "triangle_kernels.h"
#include "workspace.h"

#include <meltlab/core/error.h>

#include <algorithm>
#include <cstring>
#include <span>
#include <stdexcept>

namespace meltlab::sim {

namespace {

// Serial: blocks of triangles compute their terms, then scatter into the corners' sum
// records in ascending triangle order.
template <class Real>
void accumulate_serial(TriMesh<Real>& m, std::vector<VertexSums<Real>>& sums) {
  const std::size_t nt = m.triangle_slots();
  sums.assign(m.vertex_slots(), VertexSums<Real>{});
  TriangleBlockTerms<Real> b;
  for (std::size_t first = 0; first < nt; first += kTriangleBlock) {
    const std::size_t count = std::min(kTriangleBlock, nt - first);
    triangle_block_terms(m, first, count, b);
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t t = first + i;
      if (!m.triangle_alive[t]) continue;
      m.face_normal[t] = Vec3<Real>(b.nx[i], b.ny[i], b.nz[i]);
      const Triangle& tri = m.triangle[t];
      for (std::size_t k = 0; k < 3; ++k)
        sums[static_cast<std::size_t>(tri[k])].lane +=
            Lanes<Real>{b.nx[i], b.ny[i], b.nz[i], b.ex[k][i], b.ey[k][i], b.ez[k][i], 0, 0};
    }
  }
}

// Parallel: blocks of triangles store their terms, then every vertex gathers its triangles
// from its (ascending) list — the same additions in the same order as above.
template <class Real>
void accumulate_parallel(TriMesh<Real>& m, Execution exec, const VertexTriangles& adj,
                         std::vector<TriangleTerms<Real>>& terms, std::vector<VertexSums<Real>>& sums) {
  const std::size_t nt = m.triangle_slots();
  terms.resize(nt);
  sums.resize(m.vertex_slots());
  const std::size_t blocks = (nt + kTriangleBlock - 1) / kTriangleBlock;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, kParallelGrain / kTriangleBlock),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      TriangleBlockTerms<Real> b;
                      for (std::size_t blk = r.begin(); blk < r.end(); ++blk) {
                        const std::size_t first = blk * kTriangleBlock;
                        const std::size_t count = std::min(kTriangleBlock, nt - first);
                        triangle_block_terms(m, first, count, b);
                        for (std::size_t i = 0; i < count; ++i) {
                          TriangleTerms<Real>& out = terms[first + i];
                          out.normal = Vec3<Real>(b.nx[i], b.ny[i], b.nz[i]);
                          for (std::size_t k = 0; k < 3; ++k)
                            out.edge[k] = Vec3<Real>(b.ex[k][i], b.ey[k][i], b.ez[k][i]);
                          if (m.triangle_alive[first + i]) m.face_normal[first + i] = out.normal;
                        }
                      }
                    });
  for_range(exec, m.vertex_slots(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v) {
      Vec3<Real> N = Vec3<Real>::Zero();
      Vec3<Real> M = Vec3<Real>::Zero();
      if (m.vertex_alive[v]) {
        for (Index t : adj.of(static_cast<Index>(v))) {
          const auto ts = static_cast<std::size_t>(t);
          N += terms[ts].normal;
          M += terms[ts].edge[corner_of(m.triangle[ts], static_cast<Index>(v))];
        }
      }
      sums[v].lane = Lanes<Real>{N.x(), N.y(), N.z(), M.x(), M.y(), M.z(), 0, 0};
    }
  });
}

// The constants of the vertex moves.
template <class Real>
struct MoveConstants {
  Real kE, kN;
  bool mean, less_equal;
};

// Lanes of eight vertex slots: the inputs and outputs of move_group().
template <class Real>
struct VertexGroup {
  const VertexSums<Real>* sums;  // 8 records
  const Index* count;            // triangles per vertex
  const std::uint8_t* alive;
  Real* position;         // 8 packed xyz triples (in and out)
  Real* normal;           // out: 8 triples
  Real* displacement;     // out: 8 triples
  Index* triangle_count;  // out
};

// Moves eight vertices (Eq. 2.10, 3.5, 3.6, 3.8) with lane arithmetic: every lane runs the
// operations of the three-component formulas in their order (dot products summed left to
// right, as in the triangle kernel), so results do not depend on how vertices are grouped. `s` is kg·kl per lane.
// A live vertex without triangles (orphan_vertex_policy: deleted by Alg. 3) and a dead slot
// do not move and get N = M = 0 (and t = 0 for a dead slot). Updates the lane maxima of |move|
// and |P| over the moved vertices.
template <class Real, DeformMode kMode>
inline void move_group(const MoveConstants<Real>& c, const VertexGroup<Real>& g, const Lanes<Real>& s,
                       Lanes<Real>& max_move, Lanes<Real>& max_coord) {
  using L = Lanes<Real>;
  using Mask = LaneMask<Real>;
  L rec[kLanes], col[kLanes];
  for (std::size_t i = 0; i < kLanes; ++i) rec[i] = g.sums[i].lane;
  transpose8<Real>(rec, col);
  typename LaneTypes<Index>::Value count8;  // 8 triangle counts, converted to Real below
  std::memcpy(&count8, g.count, sizeof(count8));
  const L count = __builtin_convertvector(count8, L);
  using Bytes [[gnu::vector_size(kLanes)]] = std::uint8_t;  // 8 flags, widened in registers
  Bytes alive8;
  std::memcpy(&alive8, g.alive, sizeof(alive8));
  const Mask live = __builtin_convertvector(alive8, Mask) != 0;
  const Mask has = live & (count > Real(0));  // live with triangles: moves

  const L n2 = col[0] * col[0] + col[1] * col[1] + col[2] * col[2];
  const L inv = lane_inverse_length<Real>(n2);  // Eq. 2.10
  const L Nx = col[0] * inv, Ny = col[1] * inv, Nz = col[2] * inv;
  L MEx = col[3], MEy = col[4], MEz = col[5];  // Eq. 3.5: sum, or mean
  if (c.mean) {
    const L divisor = has ? count : broadcast<Real>(1);
    MEx = MEx / divisor, MEy = MEy / divisor, MEz = MEz / divisor;
  }
  L mx, my, mz;
  if constexpr (kMode == DeformMode::kCombined) {
    // M_N = -N, so Eq. 3.6's agreement test M_N·M_E > 0 is N·M_E < 0 (Alg. 1: <=).
    const L d = Nx * MEx + Ny * MEy + Nz * MEz;
    const Mask combined = c.less_equal ? d <= Real(0) : d < Real(0);
    const Real mkN = -c.kN;
    mx = combined ? (c.kE * MEx - c.kN * Nx) * s : (mkN * Nx) * s;
    my = combined ? (c.kE * MEy - c.kN * Ny) * s : (mkN * Ny) * s;
    mz = combined ? (c.kE * MEz - c.kN * Nz) * s : (mkN * Nz) * s;
  } else if constexpr (kMode == DeformMode::kNormalOnly) {
    const Real mkN = -c.kN;
    mx = (mkN * Nx) * s, my = (mkN * Ny) * s, mz = (mkN * Nz) * s;
  } else {
    mx = (c.kE * MEx) * s, my = (c.kE * MEy) * s, mz = (c.kE * MEz) * s;
  }
  const L zero{};
  mx = has ? mx : zero, my = has ? my : zero, mz = has ? mz : zero;
  L px, py, pz;
  deinterleave3<Real>(g.position, px, py, pz);
  px = has ? px + mx : px, py = has ? py + my : py, pz = has ? pz + mz : pz;  // Eq. 3.8
  interleave3<Real>(g.position, px, py, pz);
  interleave3<Real>(g.normal, has ? Nx : zero, has ? Ny : zero, has ? Nz : zero);
  interleave3<Real>(g.displacement, mx, my, mz);
  for (std::size_t i = 0; i < kLanes; ++i) g.triangle_count[i] = g.alive[i] ? g.count[i] : 0;
  max_move = lane_max<Real>(max_move,
                            lane_max<Real>(lane_max<Real>(lane_abs<Real>(mx), lane_abs<Real>(my)), lane_abs<Real>(mz)));
  const L coord = lane_max<Real>(lane_max<Real>(lane_abs<Real>(px), lane_abs<Real>(py)), lane_abs<Real>(pz));
  max_coord = lane_max<Real>(max_coord, has ? coord : zero);
}

// Moves every vertex from its sums, eight slots at a time (the last few of a range through
// padded copies, so every vertex runs the same code); returns a bound on how far any vertex
// moved: the largest |move| plus the rounding of P + move (half an ulp of the largest
// coordinate per component). `scale_at` is kg·kl: one number for a constant kl, else a
// function of the vertex slot, called for the vertices that move.
template <class Real, DeformMode kMode, class ScaleAt>
double move_vertices(TriMesh<Real>& m, const MeltParams& p, Execution exec, const VertexTriangles& adj,
                     const std::vector<VertexSums<Real>>& sums, const ScaleAt& scale_at) {
  const MoveConstants<Real> c{static_cast<Real>(p.kE), static_cast<Real>(p.kN), p.edge_sum == EdgeSumMode::kMean,
                              p.tie == TieRule::kLessEqual};
  const std::span<const Index> counts = adj.counts();
  std::atomic<double> max_move{0.0}, max_coord{0.0};
  auto atomic_max = [](std::atomic<double>& a, double x) {
    double cur = a.load(std::memory_order_relaxed);
    while (x > cur && !a.compare_exchange_weak(cur, x, std::memory_order_relaxed)) {
    }
  };
  for_range(exec, m.vertex_slots(), [&](std::size_t begin, std::size_t end) {
    Lanes<Real> lane_move{}, lane_coord{};
    auto scale = [&](std::size_t v, const Index* count, const std::uint8_t* alive) {
      if constexpr (std::is_arithmetic_v<ScaleAt>) {
        return broadcast<Real>(scale_at);
      } else {
        Lanes<Real> s{};
        for (std::size_t i = 0; i < kLanes; ++i)
          if (alive[i] && count[i] > 0) s[i] = scale_at(v + i);
        return s;
      }
    };
    std::size_t v = begin;
    for (; v + kLanes <= end; v += kLanes) {
      const VertexGroup<Real> g{&sums[v],
                                &counts[v],
                                &m.vertex_alive[v],
                                m.position[v].data(),
                                m.normal[v].data(),
                                m.displacement[v].data(),
                                &m.triangle_count[v]};
      move_group<Real, kMode>(c, g, scale(v, g.count, g.alive), lane_move, lane_coord);
    }
    if (v < end) {  // the last n < 8 slots, through padded copies (padding lanes are dead)
      const std::size_t n = end - v;
      VertexSums<Real> pad_sums[kLanes] = {};
      Index pad_count[kLanes] = {}, pad_tcount[kLanes] = {};
      std::uint8_t pad_alive[kLanes] = {};
      Real pad_pos[3 * kLanes] = {}, pad_normal[3 * kLanes], pad_disp[3 * kLanes];
      std::copy_n(&sums[v], n, pad_sums);
      std::copy_n(&counts[v], n, pad_count);
      std::copy_n(&m.vertex_alive[v], n, pad_alive);
      std::copy_n(m.position[v].data(), 3 * n, pad_pos);
      move_group<Real, kMode>(c, {pad_sums, pad_count, pad_alive, pad_pos, pad_normal, pad_disp, pad_tcount},
                              scale(v, pad_count, pad_alive), lane_move, lane_coord);
      std::copy_n(pad_pos, 3 * n, m.position[v].data());
      std::copy_n(pad_normal, 3 * n, m.normal[v].data());
      std::copy_n(pad_disp, 3 * n, m.displacement[v].data());
      std::copy_n(pad_tcount, n, &m.triangle_count[v]);
    }
    Real local_move = 0, local_coord = 0;
    for (std::size_t i = 0; i < kLanes; ++i) {
      local_move = std::max(local_move, lane_move[i]);
      local_coord = std::max(local_coord, lane_coord[i]);
    }
    atomic_max(max_move, static_cast<double>(local_move));
    atomic_max(max_coord, static_cast<double>(local_coord));
  });
  // |move| <= sqrt(3) * max component; rounding of each component <= eps * |coordinate|.
  constexpr double kSqrt3 = 1.7320508075688772;
  return kSqrt3 * (max_move.load() + static_cast<double>(std::numeric_limits<Real>::epsilon()) * max_coord.load());
}

template <class Real, class ScaleAt>
double move_vertices(TriMesh<Real>& m, const MeltParams& p, Execution exec, const VertexTriangles& adj,
                     const std::vector<VertexSums<Real>>& sums, const ScaleAt& scale_at) {
  switch (p.deform) {
    case DeformMode::kCombined:
      return move_vertices<Real, DeformMode::kCombined>(m, p, exec, adj, sums, scale_at);
    case DeformMode::kNormalOnly:
      return move_vertices<Real, DeformMode::kNormalOnly>(m, p, exec, adj, sums, scale_at);
    case DeformMode::kEdgeOnly:
      return move_vertices<Real, DeformMode::kEdgeOnly>(m, p, exec, adj, sums, scale_at);
  }
  throw std::logic_error("deform: unknown DeformMode");
}

}  // namespace

template <class Real>
void deform_pass(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec, MeltWorkspace& ws) {
  prepare_workspace(ws, m);
  std::vector<VertexSums<Real>>& sums = ws.vertex_sums<Real>();
  if (exec == Execution::kSerial || m.triangle_slots() < 2 * kParallelGrain)
    accumulate_serial(m, sums);
  else
    accumulate_parallel(m, exec, ws.adj, ws.triangle_terms<Real>(), sums);
  // A constant kl costs nothing per vertex: s = kg·kl is folded into one number.
  if (kl.is_constant()) {
    const auto s = static_cast<Real>(p.kg * kl.value(Vec3<double>::Zero()));
    ws.cycle_move_bound = move_vertices(m, p, exec, ws.adj, sums, s);
  } else {
    ws.cycle_move_bound = move_vertices(m, p, exec, ws.adj, sums, [&](std::size_t v) {
      return static_cast<Real>(p.kg * kl.value(m.position[v].template cast<double>()));
    });
  }
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
