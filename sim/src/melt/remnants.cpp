// Removal of inverted parts (harness safety net, see MeltParams::remnant_check_every).
// Connected parts come from a union-find over the live triangles; each part's signed
// volume is the divergence-theorem sum of its triangles, accumulated in double. A closed
// part with correct (outward) orientation has positive volume; <= 0 means it is inside out
// or flat, i.e. it has melted through itself.

#include "../mesh/union_find.h"
#include "workspace.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace meltlab::sim {

namespace {

// Unites the corners of every live triangle, in triangle order, by Rem's algorithm with splicing
// (UnionFind::unite): a part's root is its smallest vertex, so after flatten() the parents
// are those of any order of the unions. One thread: it measured faster than the earlier unions on
// the threads by compare-exchange (serial finds with path halving, per check: 84, 492 and 6 686 µs on
// the geodesic 32k, the bunny and the dragon; on two threads 102, 416 and 5 498; spliced, serial:
// 59, 287 and 3 966; docs/melt-core.md, issue 20 step 30).
template <class Real>
void unite_corners(const TriMesh<Real>& m, UnionFind& parts) {
  const std::size_t nt = m.triangle_slots();
  for (std::size_t t = 0; t < nt; ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    parts.unite(tri[0], tri[1]);
    parts.unite(tri[0], tri[2]);
  }
}

// The connected parts of the live triangles (`parts`: every slot's root after flatten()), found
// afresh only when the triangles or their alive flags differ from those of the last time (kept in
// `tris` and `alive`): the parts are a function of these and the slot count alone. Between two
// checks a melt usually changes no triangle (the 32k meshes of the benchmark merge none), and
// comparing the arrays costs a tenth of the unions.
template <class Real>
void find_parts(const TriMesh<Real>& m, UnionFind& parts, std::vector<Triangle>& tris,
                std::vector<std::uint8_t>& alive) {
  const std::size_t nv = m.vertex_slots(), nt = m.triangle_slots();
  static_assert(sizeof(Triangle) == 3 * sizeof(Index));  // no padding: memcmp compares the corners
  const bool same = parts.parent.size() == nv && tris.size() == nt && alive.size() == nt &&
                    (nt == 0 || (std::memcmp(alive.data(), m.triangle_alive.data(), nt) == 0 &&
                                 std::memcmp(tris.data(), m.triangle.data(), nt * sizeof(Triangle)) == 0));
  if (same) return;
  parts.reset(nv);
  unite_corners(m, parts);
  parts.flatten();
  tris = m.triangle;
  alive = m.triangle_alive;
}

// Each part's six-fold signed volume, the sum of its triangles' terms in triangle order, into
// six_volume (zero on entry). Consecutive triangles mostly lie in one part, so its sum is kept in a
// register for the run of them (written back when the part changes, read again when it comes back):
// the same additions in the same order as adding into six_volume each time, without waiting on the
// store of one addition to load the next (about a third of this pass on the 32k meshes,
// docs/melt-core.md, issue 20 step 20).
template <class Real, class Term>
void sum_volumes_in_order(const TriMesh<Real>& m, const std::vector<Index>& parent, const Term& term,
                          std::vector<double>& six_volume) {
  const std::size_t nt = m.triangle_slots();
  Index run_part = 0;
  double run_sum = six_volume.empty() ? 0.0 : six_volume[0];
  for (std::size_t t = 0; t < nt; ++t) {
    if (!m.triangle_alive[t]) continue;
    const Index part = parent[static_cast<std::size_t>(m.triangle[t][0])];
    if (part != run_part) {
      six_volume[static_cast<std::size_t>(run_part)] = run_sum;
      run_part = part;
      run_sum = six_volume[static_cast<std::size_t>(part)];
    }
    run_sum += term(t);
  }
  if (!six_volume.empty()) six_volume[static_cast<std::size_t>(run_part)] = run_sum;
}

// The parts' volumes summed in chunks of triangles on the threads, written to ws.part_six_volume
// when every part's sign is certified (see remove_inverted_parts_pass); false otherwise (then
// ws.part_six_volume is left as it was).
template <class Real, class Term>
bool sum_volumes_in_chunks(const TriMesh<Real>& m, const std::vector<Index>& parent, const Term& term,
                           MeltWorkspace& ws) {
  const std::size_t nt = m.triangle_slots();
  const std::size_t chunks = (nt + kParallelGrain - 1) / kParallelGrain;
  using VolumeRun = MeltWorkspace::VolumeRun;
  std::vector<std::vector<VolumeRun>>& runs = ws.volume_runs;
  runs.resize(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t k) {
    std::vector<VolumeRun>& out = runs[k];
    out.clear();
    VolumeRun run{-1, 0.0, 0.0, 0};
    for (std::size_t t = k * kParallelGrain; t < std::min(nt, (k + 1) * kParallelGrain); ++t) {
      if (!m.triangle_alive[t]) continue;
      const Index part = parent[static_cast<std::size_t>(m.triangle[t][0])];
      if (part != run.part) {
        if (run.terms > 0) out.push_back(run);
        run = {part, 0.0, 0.0, 0};
      }
      const double x = term(t);
      run.sum += x, run.magnitude += std::abs(x), ++run.terms;
    }
    if (run.terms > 0) out.push_back(run);
  });
  // Each part's runs in chunk order (a stable sort keeps it): one deterministic sum per part.
  std::vector<VolumeRun>& all = ws.volume_runs_sorted;
  all.clear();
  for (const std::vector<VolumeRun>& chunk : runs) all.insert(all.end(), chunk.begin(), chunk.end());
  std::stable_sort(all.begin(), all.end(), [](const VolumeRun& a, const VolumeRun& b) { return a.part < b.part; });
  // The parts' totals (in place, at the front of `all`), each certified before any is written.
  constexpr double u = std::numeric_limits<double>::epsilon() / 2;
  std::size_t parts = 0;
  for (std::size_t i = 0; i < all.size(); ++parts) {
    VolumeRun part = all[i++];
    for (; i < all.size() && all[i].part == part.part; ++i)
      part.sum += all[i].sum, part.magnitude += all[i].magnitude, part.terms += all[i].terms;
    // 2 γ(n-1) Σ|terms| <= 4 (n + 1) u × the computed Σ|terms| (itself within γ(n-1) of the exact; n u < 1e-6).
    const auto n = static_cast<double>(part.terms);
    if (!(std::abs(part.sum) > 4.0 * (n + 1.0) * u * part.magnitude)) return false;
    all[parts] = part;
  }
  for (std::size_t k = 0; k < parts; ++k) ws.part_six_volume[static_cast<std::size_t>(all[k].part)] = all[k].sum;
  return true;
}

}  // namespace

template <class Real>
std::int64_t remove_inverted_parts_pass(TriMesh<Real>& m, MeltWorkspace& ws, Execution exec) {
  const std::size_t nv = m.vertex_slots(), nt = m.triangle_slots();
  UnionFind& parts = ws.remnant_parts;
  find_parts(m, parts, ws.remnant_triangles, ws.remnant_alive);
  const std::vector<Index>& parent = parts.parent;  // each slot's root
  // Corners from the packed copy of the positions when it is current (the same numbers; one
  // cache line per corner instead of three).
  const std::vector<Real>& packed = ws.packed_positions<Real>();
  const bool use_packed = ws.packed_valid && packed.size() == 3 * nv + 1;
  auto corner = [&](Index v) {
    const auto vs = static_cast<std::size_t>(v);
    if (use_packed) return Vec3<double>(packed[3 * vs], packed[3 * vs + 1], packed[3 * vs + 2]);
    return Vec3<double>(m.position[vs].template cast<double>());
  };
  auto term = [&](std::size_t t) {
    const Triangle& tri = m.triangle[t];
    const Vec3<double> a = corner(tri[0]), b = corner(tri[1]), c = corner(tri[2]);
    return a.dot(b.cross(c));
  };
  std::vector<double>& six_volume = ws.part_six_volume;
  six_volume.assign(nv, 0.0);
  // On the threads: each part's volume summed in chunks, then the chunks' sums in chunk order. Only
  // the sign decides, and it must be the sign of the ordered sum below (the serial check's): both
  // sums add the same n terms, each within γ(n-1)·Σ|terms| of their exact sum, so a chunked sum
  // further from zero than twice that has the ordered sum's sign (and the ordered sum is not 0).
  // A part nearer zero (a flat remnant) sends the check to the ordered sum.
  const bool chunked = exec == Execution::kParallel && nt >= 2 * kParallelGrain;
  if (!(chunked && sum_volumes_in_chunks(m, parent, term, ws))) sum_volumes_in_order(m, parent, term, six_volume);
  std::int64_t removed = 0;
  std::vector<std::uint8_t>& doomed = ws.part_doomed;
  doomed.assign(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    if (!m.vertex_alive[v] || parent[v] != static_cast<Index>(v)) continue;
    if (ws.adj.built() && ws.adj.of(static_cast<Index>(v)).empty()) continue;
    if (six_volume[v] <= 0.0) {
      doomed[v] = 1;
      ++removed;
    }
  }
  if (removed == 0) return 0;
  ws.schedule.invalidate();
  for (std::size_t t = 0; t < nt; ++t)
    if (m.triangle_alive[t] && doomed[static_cast<std::size_t>(parent[static_cast<std::size_t>(m.triangle[t][0])])])
      m.triangle_alive[t] = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!m.vertex_alive[v] || !doomed[static_cast<std::size_t>(parent[v])]) continue;
    m.vertex_alive[v] = 0;
    m.triangle_count[v] = 0;
    if (ws.adj.built()) ws.adj.assign(static_cast<Index>(v), {});
  }
  return removed;
}

template <class Real>
std::int64_t remove_inverted_parts(TriMesh<Real>& m, Execution exec) {
  MeltWorkspace ws;
  return remove_inverted_parts_pass(m, ws, exec);
}

template std::int64_t remove_inverted_parts_pass(TriMesh<float>&, MeltWorkspace&, Execution);
template std::int64_t remove_inverted_parts_pass(TriMesh<double>&, MeltWorkspace&, Execution);
template std::int64_t remove_inverted_parts(TriMesh<float>&, Execution);
template std::int64_t remove_inverted_parts(TriMesh<double>&, Execution);

}  // namespace meltlab::sim
