// The OpenMesh speed peer runs the same model as sim::MeltSimulator: Alg. 1's closed form,
// a closed manifold every cycle, a volume that never grows, and a volume curve that follows
// MeltSimulator's until the two collapse passes make different choices.

#include <meltlab/datasets/procedural.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/melt.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "hand_meshes.h"
#include "openmesh_peer.h"

namespace meltlab::bench {
namespace {

using sim::IndexedMesh;
using sim::MeltParams;
using V3 = sim::Vec3<double>;

// Closed forms below are evaluated with a handful of operations in the peer's precision.
constexpr double kExactDouble = 1e-12;
constexpr double kExactFloat = 1e-6;

MeltParams params(double kE, double kN, double kg = 1.0, double kr = 0.0) {
  MeltParams p;
  p.kE = kE;
  p.kN = kN;
  p.kg = kg;
  p.kr = kr;
  return p;
}

MeltParams relative_params(const IndexedMesh& m, double ke_rel, double kr_rel) {
  const double L0 = sim::mesh_quality(sim::TriMesh<double>::from_indexed(m)).mean_edge_length;
  return params(ke_rel * L0, ke_rel * L0 / 100.0, 1.0, kr_rel * L0);
}

double volume_of(const IndexedMesh& m) { return sim::mesh_volume(sim::TriMesh<double>::from_indexed(m)); }

// Octahedron vertex (1,0,0): the four unit edges (-1,±1,0)/√2, (-1,0,±1)/√2 average to
// M_E = (-1/√2, 0, 0) and N = (1,0,0); convex, so it moves by -(kE/√2 + kN)·kg along x.
template <class Real>
void check_octahedron_closed_form(double tolerance) {
  const double kE = 0.01, kN = 0.0001, kg = 0.5;
  OpenMeshMeltPeerT<Real> peer(test::octahedron(1.0), params(kE, kN, kg));
  const sim::CycleReport r = peer.step();
  EXPECT_EQ(r.merged_vertices, 0);
  EXPECT_EQ(r.live_vertices, 6);
  EXPECT_EQ(r.live_triangles, 8);
  const IndexedMesh m = peer.mesh();
  ASSERT_EQ(m.V.size(), 6u);
  const double expected = 1.0 - (kE / std::sqrt(2.0) + kN) * kg;
  EXPECT_NEAR(m.V[0].x(), expected, tolerance);
  EXPECT_NEAR(m.V[0].y(), 0.0, tolerance);
  EXPECT_NEAR(m.V[0].z(), 0.0, tolerance);
  for (std::size_t v = 0; v < 6; ++v) EXPECT_NEAR(m.V[v].norm(), expected, tolerance) << "v" << v;
}

TEST(OpenMeshPeer, OctahedronMatchesClosedForm) {
  check_octahedron_closed_form<double>(kExactDouble);
  check_octahedron_closed_form<float>(kExactFloat);
}

// A dimple: the +z apex pushed below its four neighbours. N = +z and M_E leans up, so
// N·M_E > 0 and only the normal term acts: the apex moves by -kN·kg along +z.
TEST(OpenMeshPeer, ConcaveVertexUsesNormalTermOnly) {
  IndexedMesh mesh = test::octahedron(1.0);
  mesh.V[4] = V3(0, 0, -0.2);
  const double kE = 0.01, kN = 0.0001;
  OpenMeshMeltPeerT<double> peer(mesh, params(kE, kN));
  peer.step();
  const V3 apex = peer.mesh().V[4];
  EXPECT_NEAR(apex.x(), 0.0, kExactDouble);
  EXPECT_NEAR(apex.y(), 0.0, kExactDouble);
  EXPECT_NEAR(apex.z(), -0.2 - kN, kExactDouble);
}

// A short edge of a tetrahedron cannot be collapsed into a valid mesh: Alg. 2 + Alg. 3
// delete it whole (one merge, two degenerate triangles, then a glued pair on 3 vertices).
TEST(OpenMeshPeer, FinalTetrahedronVanishes) {
  OpenMeshMeltPeerT<double> peer(test::tetrahedron_fig_2_13(), params(0.0, 0.0, 1.0, 10.0));
  const sim::CycleReport r = peer.step();
  EXPECT_TRUE(peer.empty());
  EXPECT_EQ(r.merged_vertices, 1);
  EXPECT_EQ(r.degenerate_triangles, 2);
  EXPECT_EQ(r.glued_triangles, 2);
  EXPECT_EQ(r.glued_vertices, 3);
  EXPECT_EQ(r.live_vertices, 0);
  EXPECT_EQ(r.live_triangles, 0);
  EXPECT_TRUE(peer.mesh().V.empty());
  EXPECT_TRUE(peer.mesh().F.empty());
}

struct MeltTotals {
  int cycles = 0;
  std::int64_t merges = 0;
  std::int64_t glued_triangles = 0;
  bool empty = false;
};

// Runs `cycles` cycles (or until empty) and checks every cycle: closed, manifold and
// valid; the report's counts equal the compacted mesh; the volume strictly decreases.
template <class Real>
MeltTotals melt_checking_invariants(const IndexedMesh& mesh, const MeltParams& p, int cycles, const std::string& name) {
  OpenMeshMeltPeerT<Real> peer(mesh, p);
  double previous_volume = volume_of(mesh);
  MeltTotals totals;
  while (totals.cycles < cycles && !peer.empty()) {
    const sim::CycleReport r = peer.step();
    ++totals.cycles;
    totals.merges += r.merged_vertices;
    totals.glued_triangles += r.glued_triangles;
    const IndexedMesh now = peer.mesh();
    const std::string where = name + " cycle " + std::to_string(totals.cycles);
    EXPECT_EQ(r.live_vertices, static_cast<std::int64_t>(now.V.size())) << where;
    EXPECT_EQ(r.live_triangles, static_cast<std::int64_t>(now.F.size())) << where;
    const sim::TopologyReport topo = sim::check_topology(sim::TriMesh<double>::from_indexed(now));
    EXPECT_TRUE(topo.valid()) << where << ": " << (topo.problems.empty() ? "" : topo.problems[0].describe());
    EXPECT_EQ(topo.counts.chi, 0) << where;
    const double volume = volume_of(now);
    EXPECT_LT(volume, previous_volume) << where;
    previous_volume = volume;
    if (::testing::Test::HasFailure()) break;
  }
  totals.empty = peer.empty();
  return totals;
}

TEST(OpenMeshPeer, StaysClosedManifoldAndShrinks) {
  const IndexedMesh sphere = datasets::icosphere(4);
  const MeltTotals s = melt_checking_invariants<double>(sphere, relative_params(sphere, 0.2, 0.5), 300, "icosphere(4)");
  EXPECT_EQ(s.cycles, 300);
  EXPECT_GT(s.merges, 0);
  const IndexedMesh c = datasets::benchmark_object('C');
  const MeltTotals m = melt_checking_invariants<float>(c, relative_params(c, 0.05, 0.5), 300, "object C");
  EXPECT_EQ(m.cycles, 300);
  EXPECT_GT(m.merges, 0);
}

// To the end: the sphere coarsens to a tetrahedron (~250 cycles), which vanishes; the mesh
// is valid every cycle on the way.
TEST(OpenMeshPeer, MeltsAwayCompletely) {
  const IndexedMesh sphere = datasets::icosphere(2);
  const MeltTotals t =
      melt_checking_invariants<double>(sphere, relative_params(sphere, 0.05, 0.5), 2000, "icosphere(2)");
  EXPECT_TRUE(t.empty) << "after " << t.cycles << " cycles";
  EXPECT_EQ(t.glued_triangles, 2) << "the last tetrahedron goes as one collapse plus one glued pair";
}

// Until the first collapse the two implementations compute the same deformation and differ
// only in summation order (rounding). After it they differ in collapse details only: the
// peer collapses pairs (midpoint, one collapse per vertex per pass), MeltSimulator merges
// clusters (cluster mean, chains). Measured on this sphere (icosphere(4), kE = 0.2 L0,
// kr = 0.5 L0, double): both start collapsing at cycle 55-60; max |V_peer - V_sim| is
// 7.1e-4 V0 (at cycle ~130), while V itself falls to 0.62 V0 by cycle 200.
// kCollapseVolumeTolerance = 2e-3 V0 is ~3x the measured gap, so it absorbs a different
// choice of marginal edges (another compiler's rounding) but not a model error: scaling the
// peer's kE and kN by 1.01 (or 0.99) opens the gap to 3.3e-3 V0 (measured).
TEST(OpenMeshPeer, VolumeTracksMeltSimulatorOnASphere) {
  constexpr double kBeforeCollapseTolerance = 1e-12;  // relative to V0: rounding only
  constexpr double kCollapseVolumeTolerance = 2e-3;   // relative to V0: see above
  const IndexedMesh sphere = datasets::icosphere(4);
  const MeltParams p = relative_params(sphere, 0.2, 0.5);
  OpenMeshMeltPeerT<double> peer(sphere, p);
  sim::MeltSimulator<double> simulator(sim::TriMesh<double>::from_indexed(sphere), p, sim::make_constant_kl(1.0));
  const double V0 = volume_of(sphere);
  std::int64_t peer_merges = 0, simulator_merges = 0;
  double max_gap = 0;
  for (int c = 1; c <= 200; ++c) {
    peer_merges += peer.step().merged_vertices;
    simulator_merges += simulator.step().merged_vertices;
    const double gap = std::abs(volume_of(peer.mesh()) - sim::mesh_volume(simulator.mesh())) / V0;
    max_gap = std::max(max_gap, gap);
    const double tolerance =
        peer_merges == 0 && simulator_merges == 0 ? kBeforeCollapseTolerance : kCollapseVolumeTolerance;
    ASSERT_LT(gap, tolerance) << "cycle " << c;
  }
  EXPECT_GT(peer_merges, 0) << "the comparison must cover collapses";
  EXPECT_GT(simulator_merges, 0) << "the comparison must cover collapses";
  RecordProperty("max_volume_gap_over_V0", std::to_string(max_gap));
}

TEST(OpenMeshPeer, RefusesWhatItDoesNotImplement) {
  MeltParams p = params(0.01, 0.0001);
  p.deform = sim::DeformMode::kNormalOnly;
  EXPECT_THROW(OpenMeshMeltPeerT<double>(test::octahedron(), p), InputError);
  p.deform = sim::DeformMode::kCombined;
  p.kg = 2.0;  // outside [0, 1]
  EXPECT_THROW(OpenMeshMeltPeerT<double>(test::octahedron(), p), InputError);
  IndexedMesh open = test::octahedron();
  open.F.pop_back();
  EXPECT_THROW(OpenMeshMeltPeerT<double>(open, params(0.01, 0.0001)), InputError);
}

}  // namespace
}  // namespace meltlab::bench
