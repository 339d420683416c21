// Alg. 1: mesh deformation (monograph §3.1–3.4, Eq. 2.9, 2.10, 3.1–3.8).
//
// Every triangle contributes its unit face normal (Eq. 2.9) and, at each corner, the unit
// edge vector to the next corner; every vertex sums them, normalises N (Eq. 2.10), takes
// the mean M_E (Eq. 3.5) and moves by kg·kl(P)·M (Eq. 3.6, 3.8).
// Serial: one sweep over the triangles scatters into the corners (sequential reads of the
// triangle array). Parallel: triangles compute their terms, then each vertex gathers from
// its triangle list. Lists are kept in ascending triangle order, so every vertex adds the
// same numbers in the same order in both modes: bitwise-identical meshes (with
// -ffp-contract=off, see cmake/flags.cmake).

#include "triangle_kernels.h"
#include "workspace.h"

#include <meltlab/sim/error.h>

#include <algorithm>

namespace meltlab::sim {

namespace {

// Serial: blocks of triangles compute their terms, then scatter into the corners in
// ascending triangle order; the sums are left in normal/displacement, the counts in
// triangle_count.
template <class Real>
void accumulate_serial(TriMesh<Real>& m) {
  const std::size_t nv = m.vertex_slots(), nt = m.triangle_slots();
  for (std::size_t v = 0; v < nv; ++v) {
    m.normal[v].setZero();
    m.displacement[v].setZero();
    m.triangle_count[v] = 0;
  }
  TriangleBlockTerms<Real> b;
  for (std::size_t first = 0; first < nt; first += kTriangleBlock) {
    const std::size_t count = std::min(kTriangleBlock, nt - first);
    triangle_block_terms(m, first, count, b);
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t t = first + i;
      if (!m.triangle_alive[t]) continue;
      const Vec3<Real> n(b.nx[i], b.ny[i], b.nz[i]);
      m.face_normal[t] = n;
      const Triangle& tri = m.triangle[t];
      for (std::size_t k = 0; k < 3; ++k) {
        const auto v = static_cast<std::size_t>(tri[k]);
        m.normal[v] += n;
        m.displacement[v] += Vec3<Real>(b.ex[k][i], b.ey[k][i], b.ez[k][i]);
        ++m.triangle_count[v];
      }
    }
  }
}

// Parallel: blocks of triangles store their terms, then every vertex gathers its triangles
// from its (ascending) list — the same additions in the same order as above.
template <class Real>
void accumulate_parallel(TriMesh<Real>& m, Execution exec, const VertexTriangles& adj,
                         std::vector<TriangleTerms<Real>>& terms) {
  const std::size_t nt = m.triangle_slots();
  terms.resize(nt);
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
      if (!m.vertex_alive[v]) continue;
      Vec3<Real> N = Vec3<Real>::Zero();
      Vec3<Real> M = Vec3<Real>::Zero();
      const auto tris = adj.of(static_cast<Index>(v));
      for (Index t : tris) {
        const auto ts = static_cast<std::size_t>(t);
        N += terms[ts].normal;
        M += terms[ts].edge[corner_of(m.triangle[ts], static_cast<Index>(v))];
      }
      m.normal[v] = N;
      m.displacement[v] = M;
      m.triangle_count[v] = static_cast<Index>(tris.size());
    }
  });
}

// Moves every vertex; returns a bound on how far any vertex moved: the largest |move| plus
// the rounding of P + move (half an ulp of the largest coordinate per component).
template <class Real, class ScaleAt>
double move_vertices(TriMesh<Real>& m, const MeltParams& p, Execution exec, const ScaleAt& scale_at) {
  const Real kE = static_cast<Real>(p.kE), kN = static_cast<Real>(p.kN);
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
      const Index count = m.triangle_count[v];
      if (count == 0) {  // orphan_vertex_policy: no triangles, no move (deleted by Alg. 3)
        m.normal[v].setZero();
        m.displacement[v].setZero();
        continue;
      }
      const Vec3<Real> N = m.normal[v] * inverse_length(m.normal[v].squaredNorm());  // Eq. 2.10
      m.normal[v] = N;
      const Vec3<Real>& Msum = m.displacement[v];
      const Vec3<Real> ME = p.edge_sum == EdgeSumMode::kMean ? Vec3<Real>(Msum / static_cast<Real>(count)) : Msum;
      const Real s = scale_at(v);  // kg · kl(P), P before the move
      Vec3<Real> move = Vec3<Real>::Zero();
      switch (p.deform) {
        case DeformMode::kCombined: {
          // M_N = -N, so Eq. 3.6's agreement test M_N·M_E > 0 is N·M_E < 0 (Alg. 1: <=).
          const Real d = N.dot(ME);
          const bool combined = p.tie == TieRule::kLessEqual ? d <= Real(0) : d < Real(0);
          move = combined ? Vec3<Real>((kE * ME - kN * N) * s) : Vec3<Real>((-kN * N) * s);
          break;
        }
        case DeformMode::kNormalOnly:
          move = (-kN * N) * s;
          break;
        case DeformMode::kEdgeOnly:
          move = (kE * ME) * s;
          break;
      }
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

}  // namespace

template <class Real>
void deform_pass(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec, MeltWorkspace& ws) {
  prepare_workspace(ws, m);
  if (exec == Execution::kSerial || m.triangle_slots() < 2 * kParallelGrain)
    accumulate_serial(m);
  else
    accumulate_parallel(m, exec, ws.adj, ws.triangle_terms<Real>());
  // A constant kl costs nothing per vertex: s = kg·kl is folded into one number.
  if (kl.is_constant()) {
    const auto s = static_cast<Real>(p.kg * kl.value(Vec3<double>::Zero()));
    ws.cycle_move_bound = move_vertices(m, p, exec, [s](std::size_t) { return s; });
  } else {
    ws.cycle_move_bound = move_vertices(m, p, exec, [&](std::size_t v) {
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
