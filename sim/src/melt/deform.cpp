// Alg. 1: mesh deformation (monograph §3.1–3.4, Eq. 2.9, 2.10, 3.1–3.8).
//
// Serial: one sweep over the triangles scatters the unit face normal and the unit edge
// vector "to the next corner" into the three corners, then one sweep over the vertices
// normalises N, forms M_E and moves the vertex. Every vertex therefore sums its triangles
// in ascending triangle index.
//
// Parallel: triangles compute their unit normal and unit edges independently; a CSR
// adjacency (vertex -> incident corners, sorted by triangle index) lets every vertex gather
// its sums in the same ascending order as the serial scatter, so the two give bitwise
// identical positions (with -ffp-contract=off, see cmake/flags.cmake).

#include "workspace.h"

#include <meltlab/sim/error.h>

#include <tbb/parallel_scan.h>

#include <algorithm>

namespace meltlab::sim {

namespace {

// Per-vertex update, identical code for both execution modes. `s` = kg · kl(P).
template <class Real>
inline void move_vertex(TriMesh<Real>& m, std::size_t v, const MeltParams& p, Real s, Real kE, Real kN) {
  const Index count = m.triangle_count[v];
  if (count == 0) {  // orphan_vertex_policy: no triangles, no move (deleted by Alg. 3)
    m.normal[v].setZero();
    m.displacement[v].setZero();
    return;
  }
  const Vec3<Real> N = normalized_or_zero<Real>(m.normal[v]);
  m.normal[v] = N;
  Vec3<Real> ME = m.displacement[v];  // accumulated unit edge vectors
  if (p.edge_sum == EdgeSumMode::kMean) ME = ME / static_cast<Real>(count);
  Vec3<Real> move = Vec3<Real>::Zero();
  switch (p.deform) {
    case DeformMode::kCombined: {
      // M_N = -N, so the agreement test M_N·M_E > 0 of Eq. 3.6 is N·M_E < 0 (Alg. 1 uses <=).
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
}

template <class Real, class ScaleAt>
void move_vertices(TriMesh<Real>& m, const MeltParams& p, Execution exec, const ScaleAt& scale_at) {
  const Real kE = static_cast<Real>(p.kE), kN = static_cast<Real>(p.kN);
  for_range(exec, m.vertex_slots(), [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      if (m.vertex_alive[v]) move_vertex(m, v, p, scale_at(v), kE, kN);
  });
}

template <class Real>
void accumulate_serial(TriMesh<Real>& m) {
  const std::size_t nv = m.vertex_slots();
  for (std::size_t v = 0; v < nv; ++v) {
    m.normal[v].setZero();
    m.displacement[v].setZero();
    m.triangle_count[v] = 0;
  }
  const std::size_t nt = m.triangle_slots();
  for (std::size_t t = 0; t < nt; ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    const auto a = static_cast<std::size_t>(tri[0]), b = static_cast<std::size_t>(tri[1]),
               c = static_cast<std::size_t>(tri[2]);
    const Vec3<Real>& pa = m.position[a];
    const Vec3<Real>& pb = m.position[b];
    const Vec3<Real>& pc = m.position[c];
    const Vec3<Real> nf = normalized_or_zero<Real>((pb - pa).cross(pc - pa));  // Eq. 2.9
    m.face_normal[t] = nf;
    m.normal[a] += nf;
    m.normal[b] += nf;
    m.normal[c] += nf;
    m.displacement[a] += normalized_or_zero<Real>(pb - pa);  // each corner: unit edge to the next corner
    m.displacement[b] += normalized_or_zero<Real>(pc - pb);
    m.displacement[c] += normalized_or_zero<Real>(pa - pc);
    ++m.triangle_count[a];
    ++m.triangle_count[b];
    ++m.triangle_count[c];
  }
}

template <class Real>
void accumulate_parallel(TriMesh<Real>& m, MeltWorkspace& ws) {
  const std::size_t nv = m.vertex_slots();
  const std::size_t nt = m.triangle_slots();
  std::vector<Real>& ue = ws.unit_edges<Real>();
  ue.resize(9 * nt);
  ws.adj_offset.resize(nv + 1);
  ws.adj_cursor.resize(nv);
  ws.adj_entry.resize(3 * nt);

  // 1. per triangle: unit face normal, unit edges; count corners per vertex.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4 * kParallelGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      std::fill(ws.adj_cursor.begin() + static_cast<std::ptrdiff_t>(r.begin()),
                                ws.adj_cursor.begin() + static_cast<std::ptrdiff_t>(r.end()), 0);
                    });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      if (!m.triangle_alive[t]) continue;
      const Triangle& tri = m.triangle[t];
      const Vec3<Real>& pa = m.position[static_cast<std::size_t>(tri[0])];
      const Vec3<Real>& pb = m.position[static_cast<std::size_t>(tri[1])];
      const Vec3<Real>& pc = m.position[static_cast<std::size_t>(tri[2])];
      m.face_normal[t] = normalized_or_zero<Real>((pb - pa).cross(pc - pa));
      const Vec3<Real> e0 = normalized_or_zero<Real>(pb - pa);
      const Vec3<Real> e1 = normalized_or_zero<Real>(pc - pb);
      const Vec3<Real> e2 = normalized_or_zero<Real>(pa - pc);
      Real* out = &ue[9 * t];
      out[0] = e0.x(), out[1] = e0.y(), out[2] = e0.z();
      out[3] = e1.x(), out[4] = e1.y(), out[5] = e1.z();
      out[6] = e2.x(), out[7] = e2.y(), out[8] = e2.z();
      for (Index v : tri) atomic_increment(ws.adj_cursor[static_cast<std::size_t>(v)]);
    }
  });
  // 2. offsets (exclusive prefix sum of the counts).
  ws.adj_offset[0] = 0;
  tbb::parallel_scan(
      tbb::blocked_range<std::size_t>(0, nv, 16 * kParallelGrain), std::int32_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::int32_t sum, bool final) {
        for (std::size_t v = r.begin(); v < r.end(); ++v) {
          sum += ws.adj_cursor[v];
          if (final) ws.adj_offset[v + 1] = sum;
        }
        return sum;
      },
      [](std::int32_t a, std::int32_t b) { return a + b; });
  // 3. fill (order within a vertex is arbitrary here) ...
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4 * kParallelGrain),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t v = r.begin(); v < r.end(); ++v) ws.adj_cursor[v] = ws.adj_offset[v];
                    });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt, kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      if (!m.triangle_alive[t]) continue;
      for (int k = 0; k < 3; ++k) {
        const auto v = static_cast<std::size_t>(m.triangle[t][static_cast<std::size_t>(k)]);
        const std::int32_t slot =
            std::atomic_ref<std::int32_t>(ws.adj_cursor[v]).fetch_add(1, std::memory_order_relaxed);
        ws.adj_entry[static_cast<std::size_t>(slot)] = static_cast<std::int32_t>(3 * t) + k;
      }
    }
  });
  // 4. ... so each vertex sorts its few entries and gathers in ascending triangle order,
  // which is exactly the order in which the serial scatter adds them.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) {
      const auto b = static_cast<std::size_t>(ws.adj_offset[v]), e = static_cast<std::size_t>(ws.adj_offset[v + 1]);
      std::int32_t* first = ws.adj_entry.data() + b;
      std::int32_t* last = ws.adj_entry.data() + e;
      for (std::int32_t* i = first + 1; i < last; ++i) {  // insertion sort: lists are short
        const std::int32_t x = *i;
        std::int32_t* j = i;
        for (; j > first && *(j - 1) > x; --j) *j = *(j - 1);
        *j = x;
      }
      Vec3<Real> N = Vec3<Real>::Zero();
      Vec3<Real> M = Vec3<Real>::Zero();
      for (const std::int32_t* i = first; i < last; ++i) {
        const auto t = static_cast<std::size_t>(*i / 3);
        const auto k = static_cast<std::size_t>(*i % 3);
        N += m.face_normal[t];
        const Real* u = &ue[9 * t + 3 * k];
        M += Vec3<Real>(u[0], u[1], u[2]);
      }
      m.normal[v] = N;
      m.displacement[v] = M;
      m.triangle_count[v] = static_cast<Index>(e - b);
    }
  });
}

}  // namespace

template <class Real>
void deform_pass(TriMesh<Real>& m, const MeltParams& p, const KlField& kl, Execution exec, MeltWorkspace& ws) {
  if (exec == Execution::kSerial || m.triangle_slots() < 2 * kParallelGrain)
    accumulate_serial(m);
  else
    accumulate_parallel(m, ws);
  // A constant kl costs nothing per vertex: s = kg·kl is folded into one number.
  if (kl.is_constant()) {
    const auto s = static_cast<Real>(p.kg * kl.value(Vec3<double>::Zero()));
    move_vertices(m, p, exec, [s](std::size_t) { return s; });
  } else {
    move_vertices(m, p, exec, [&](std::size_t v) {
      return static_cast<Real>(p.kg * kl.value(m.position[v].template cast<double>()));  // pre-move P
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
