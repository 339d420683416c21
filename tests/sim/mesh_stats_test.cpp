// The per-cycle statistics (MeshStatistics): the Euler counts equal the full topology check's,
// the quality measures equal a plain serial evaluation bit for bit (pairing by an ordered map,
// sums in triangle and edge order), on hand-built and melted meshes with dead slots, open
// edges, non-manifold edges and degenerate triangles; any number of threads gives the same bits,
// and reusing one object across meshes changes nothing.

#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/melt.h>
#include <meltlab/sim/mesh_stats.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace meltlab::sim {
namespace {

// The quality measures by their definitions, serially: per live triangle in slot order, then per
// undirected edge in (lo, hi) order, its uses in triangle order (a std::map of the pairs).
QualityReport reference_quality(const TriMesh<double>& m) {
  QualityReport r;
  r.min_q = 1.0;
  r.bbox_min.setConstant(std::numeric_limits<double>::infinity());
  r.bbox_max.setConstant(-std::numeric_limits<double>::infinity());
  std::map<std::pair<Index, Index>, std::vector<std::size_t>> uses;
  std::vector<Vec3<double>> unit_normal(m.triangle_slots(), Vec3<double>::Zero());
  double sum_s = 0, sum_q = 0, six_v = 0;
  std::int64_t nf = 0;
  for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    const Vec3<double> a = m.position[static_cast<std::size_t>(tri[0])];
    const Vec3<double> b = m.position[static_cast<std::size_t>(tri[1])];
    const Vec3<double> c = m.position[static_cast<std::size_t>(tri[2])];
    for (const Vec3<double>* p : {&a, &b, &c}) {
      r.bbox_min = r.bbox_min.cwiseMin(*p);
      r.bbox_max = r.bbox_max.cwiseMax(*p);
    }
    const Vec3<double> n = (b - a).cross(c - a);
    r.area += 0.5 * n.norm();
    six_v += a.dot(b.cross(c));
    if (n.squaredNorm() > 0) unit_normal[t] = n.normalized();
    sum_s += triangle_twist_deg(a, b, c);
    const double q = triangle_quality(a, b, c);
    sum_q += q;
    r.min_q = std::min(r.min_q, q);
    ++nf;
    for (int k = 0; k < 3; ++k) {
      const Index u = tri[static_cast<std::size_t>(k)], w = tri[static_cast<std::size_t>((k + 1) % 3)];
      uses[{std::min(u, w), std::max(u, w)}].push_back(t);
    }
  }
  r.volume = six_v / 6.0;
  if (nf == 0) return QualityReport{};
  r.Qs = sum_s / static_cast<double>(nf);
  r.Qq = sum_q / static_cast<double>(nf);
  double sum_d = 0, sum_len = 0;
  for (const auto& [edge, tris] : uses) {
    sum_len +=
        (m.position[static_cast<std::size_t>(edge.first)] - m.position[static_cast<std::size_t>(edge.second)]).norm();
    if (tris.size() != 2) continue;
    const double d = dihedral_deg(unit_normal[tris[0]], unit_normal[tris[1]]);
    sum_d += d;
    r.max_d = std::max(r.max_d, d);
    ++r.edges;
  }
  r.Qd = r.edges > 0 ? sum_d / static_cast<double>(r.edges) : 0.0;
  r.mean_edge_length = sum_len / static_cast<double>(uses.size());
  return r;
}

// Exact equality of every field (== on doubles: the same bits for numbers that are not NaN).
void expect_same(const MeshStats& a, const QualityReport& q, const EulerCounts& c, const std::string& what) {
  EXPECT_EQ(a.quality.Qs, q.Qs) << what;
  EXPECT_EQ(a.quality.Qd, q.Qd) << what;
  EXPECT_EQ(a.quality.Qq, q.Qq) << what;
  EXPECT_EQ(a.quality.max_d, q.max_d) << what;
  EXPECT_EQ(a.quality.min_q, q.min_q) << what;
  EXPECT_EQ(a.quality.volume, q.volume) << what;
  EXPECT_EQ(a.quality.area, q.area) << what;
  EXPECT_EQ(a.quality.bbox_min, q.bbox_min) << what;
  EXPECT_EQ(a.quality.bbox_max, q.bbox_max) << what;
  EXPECT_EQ(a.quality.mean_edge_length, q.mean_edge_length) << what;
  EXPECT_EQ(a.quality.edges, q.edges) << what;
  EXPECT_EQ(a.topology.V, c.V) << what;
  EXPECT_EQ(a.topology.E, c.E) << what;
  EXPECT_EQ(a.topology.F, c.F) << what;
  EXPECT_EQ(a.topology.H, c.H) << what;
  EXPECT_EQ(a.topology.S, c.S) << what;
  EXPECT_EQ(a.topology.G, c.G) << what;
  EXPECT_EQ(a.topology.chi, c.chi) << what;
  EXPECT_EQ(a.topology.genus_valid, c.genus_valid) << what;
}

// Meshes that exercise every branch: closed genus 0 and 1, two components, an open mesh, a
// non-manifold edge (three faces), a degenerate triangle, dead slots, and melted meshes of
// more than two parallel grains (2048) with merges, dead slots and unreferenced vertices.
std::vector<std::pair<std::string, TriMesh<double>>> meshes() {
  std::vector<std::pair<std::string, TriMesh<double>>> out;
  auto add = [&](std::string name, const IndexedMesh& m) {
    out.emplace_back(std::move(name), TriMesh<double>::from_indexed(m));
  };
  add("icosphere", datasets::icosphere(2));
  add("torus", datasets::torus(1.0, 0.3, 24, 12));
  IndexedMesh two = datasets::icosphere(1);
  const IndexedMesh cube = datasets::cube_triangles(0.5);
  const auto base = static_cast<Index>(two.V.size());
  for (const auto& v : cube.V) two.V.push_back(v + Vec3<double>(3, 0, 0));
  for (const auto& f : cube.F) two.F.push_back({f[0] + base, f[1] + base, f[2] + base});
  add("two components", two);
  IndexedMesh open = datasets::icosphere(1);
  open.F.pop_back();
  add("open", open);
  IndexedMesh fin = datasets::cube_triangles(1.0);
  fin.V.push_back({0.5, 0.5, 3.0});
  fin.F.push_back({fin.F[0][0], fin.F[0][1], static_cast<Index>(fin.V.size() - 1)});
  add("non-manifold edge", fin);
  IndexedMesh degenerate = datasets::icosphere(1);
  degenerate.F.push_back({0, 0, 1});
  degenerate.F.push_back({2, 5, 5});
  add("degenerate", degenerate);
  TriMesh<double> dead = TriMesh<double>::from_indexed(datasets::icosphere(2));
  dead.triangle_alive[3] = 0;
  dead.triangle_alive[40] = 0;
  out.emplace_back("dead slots", dead);
  out.emplace_back("empty", TriMesh<double>{});
  for (const char which : {'B', 'C'}) {
    const IndexedMesh m = datasets::benchmark_object(which);
    MeltSimulator<double> s(TriMesh<double>::from_indexed(m), relative_melt_params(m, 0.05, 0.5), make_constant_kl(1.0),
                            Execution::kSerial);
    for (int c = 0; c < 120; ++c) s.step();
    out.emplace_back(std::string("object ") + which + " melted 120 cycles", s.mesh());
  }
  return out;
}

TEST(MeshStatistics, EqualsTheFullTopologyCheckAndASerialReferenceBitForBit) {
  MeshStatistics stats;  // one object for all: its kept buffers must not leak between meshes
  for (const auto& [name, m] : meshes()) {
    const MeshStats& s = stats.compute(m);
    expect_same(s, reference_quality(m), check_topology(m).counts, name);
    // The quality's own entry point and a fresh object agree too.
    expect_same(MeshStatistics().compute(m), mesh_quality(m), euler_counts(m), name + " (fresh)");
  }
}

TEST(MeshStatistics, AnyNumberOfThreadsGivesTheSameBits) {
  const auto all = meshes();
  for (const auto& [name, m] : all) {
    MeshStatistics one_stats, many_stats;
    MeshStats one, many;
    tbb::task_arena(1).execute([&] { one = one_stats.compute(m); });
    tbb::task_arena(4).execute([&] { many = many_stats.compute(m); });
    expect_same(many, one.quality, one.topology, name);
  }
}

TEST(MeshStatistics, FloatMeshesAreMeasuredInDouble) {
  const IndexedMesh m = datasets::benchmark_object('C');
  const MeshStats s64 = MeshStatistics().compute(TriMesh<double>::from_indexed(m));
  const TriMesh<float> f = TriMesh<double>::from_indexed(m).cast<float>();
  const MeshStats s32 = MeshStatistics().compute(f);
  EXPECT_EQ(s32.quality.volume, reference_quality(f.cast<double>()).volume) << "the float positions, summed in double";
  // Tolerance: float positions carry a relative rounding of 2^-24 ≈ 6e-8, so volumes and areas
  // move by a few times that; 1e-6 relative is 16x that bound, far below any real change.
  EXPECT_NEAR(s32.quality.volume, s64.quality.volume, 1e-6 * std::abs(s64.quality.volume));
  EXPECT_NEAR(s32.quality.area, s64.quality.area, 1e-6 * s64.quality.area);
  EXPECT_EQ(s32.topology.E, s64.topology.E);
  EXPECT_EQ(s32.topology.chi, 0);
}

}  // namespace
}  // namespace meltlab::sim
