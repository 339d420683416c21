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
// triangle count is the length of its list.

#include "triangle_kernels.h"
#include "workspace.h"

#include <meltlab/sim/error.h>

#include <algorithm>
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
            typename VertexSums<Real>::Lanes{b.nx[i], b.ny[i], b.nz[i], b.ex[k][i], b.ey[k][i], b.ez[k][i], 0, 0};
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
                          for (std::size_t k = 0; k < 3; ++k) out.edge[k] = Vec3<Real>(b.ex[k][i], b.ey[k][i], b.ez[k][i]);
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
      sums[v].lane = typename VertexSums<Real>::Lanes{N.x(), N.y(), N.z(), M.x(), M.y(), M.z(), 0, 0};
    }
  });
}

// Moves every vertex from its sums (Eq. 2.10, 3.5, 3.6, 3.8); returns a bound on how far any
// vertex moved: the largest |move| plus the rounding of P + move (half an ulp of the largest
// coordinate per component). `scale_at` is kg·kl: one number for a constant kl, else a
// function of the vertex slot. (A version that moved blocks of vertices through plain
// arrays, vectorised, measured twice as slow as this loop: the gathers and scatters between
// the records and the arrays cost more than the arithmetic they vectorise.)
template <class Real, DeformMode kMode, class ScaleAt>
double move_vertices(TriMesh<Real>& m, const MeltParams& p, Execution exec, const VertexTriangles& adj,
                     const std::vector<VertexSums<Real>>& sums, const ScaleAt& scale_at) {
  const Real kE = static_cast<Real>(p.kE), kN = static_cast<Real>(p.kN);
  const bool mean = p.edge_sum == EdgeSumMode::kMean;
  const bool less_equal = p.tie == TieRule::kLessEqual;
  std::atomic<double> max_move{0.0}, max_coord{0.0};
  auto atomic_max = [](std::atomic<double>& a, double x) {
    double cur = a.load(std::memory_order_relaxed);
    while (x > cur && !a.compare_exchange_weak(cur, x, std::memory_order_relaxed)) {
    }
  };
  for_range(exec, m.vertex_slots(), [&](std::size_t begin, std::size_t end) {
    Real local_move = 0, local_coord = 0;
    for (std::size_t v = begin; v < end; ++v) {
      if (!m.vertex_alive[v]) continue;
      const Index count = adj.count(static_cast<Index>(v));
      m.triangle_count[v] = count;
      if (count == 0) {  // orphan_vertex_policy: no triangles, no move (deleted by Alg. 3)
        m.normal[v].setZero();
        m.displacement[v].setZero();
        continue;
      }
      const auto& sum = sums[v].lane;
      const Vec3<Real> Nsum(sum[0], sum[1], sum[2]), Msum(sum[3], sum[4], sum[5]);
      const Vec3<Real> N = Nsum * inverse_length(Nsum.squaredNorm());  // Eq. 2.10
      const Vec3<Real> ME = mean ? Vec3<Real>(Msum / static_cast<Real>(count)) : Msum;  // Eq. 3.5
      Real s;  // kg · kl(P), P before the move
      if constexpr (std::is_arithmetic_v<ScaleAt>)
        s = scale_at;
      else
        s = scale_at(v);
      Vec3<Real> move;
      if constexpr (kMode == DeformMode::kCombined) {
        // M_N = -N, so Eq. 3.6's agreement test M_N·M_E > 0 is N·M_E < 0 (Alg. 1: <=).
        const Real d = N.dot(ME);
        const bool combined = less_equal ? d <= Real(0) : d < Real(0);
        move = combined ? Vec3<Real>((kE * ME - kN * N) * s) : Vec3<Real>((-kN * N) * s);
      } else if constexpr (kMode == DeformMode::kNormalOnly) {
        move = (-kN * N) * s;
      } else {
        move = (kE * ME) * s;
      }
      m.normal[v] = N;
      m.displacement[v] = move;
      m.position[v] += move;
      local_move = std::max(local_move, move.cwiseAbs().maxCoeff());
      local_coord = std::max(local_coord, m.position[v].cwiseAbs().maxCoeff());
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
