// Voxelization and isosurface extraction of the reference solver (sim/physics).
#include <meltlab/datasets/molds.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/physics/enthalpy.h>
#include <meltlab/sim/physics/isosurface.h>
#include <meltlab/sim/physics/voxelize.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

namespace meltlab::sim::physics {
namespace {

IndexedMesh box(double ex, double ey, double ez, const Eigen::Vector3d& lo) {
  auto m = datasets::cube_triangles(1.0);
  Eigen::Vector3d a = m.V[0], b = m.V[0];
  for (auto& v : m.V) a = a.cwiseMin(v), b = b.cwiseMax(v);
  for (auto& v : m.V) {
    const Eigen::Vector3d u = (v - a).cwiseQuotient(b - a);
    v = lo + Eigen::Vector3d(ex * u.x(), ey * u.y(), ez * u.z());
  }
  return m;
}

double volume_of(const IndexedMesh& m) { return mesh_volume(TriMesh<double>::from_indexed(m)); }

TEST(Voxelize, BoxVolumeIsExactUpToSampling) {
  // A box not aligned with the cells: z-overlaps are exact; in x, y each sub-ray column is
  // either in or out, so the error is at most one sub-sample strip per side: 2(ex+ey)·ez·h/S.
  const double h = 1e-3;
  const auto m = box(0.0213, 0.0171, 0.0097, Eigen::Vector3d(0.0003, -0.0021, 0.0));
  VoxelizeOptions vo;
  vo.h_m = h;
  vo.subsamples = 4;
  const auto g = voxelize_fraction(m, vo);
  const double V = 0.0213 * 0.0171 * 0.0097;
  const double bound = 2 * (0.0213 + 0.0171) * 0.0097 * h / 4;
  EXPECT_NEAR(grid_volume(g), V, bound);
  // floor at the mesh bottom: the block rests on layer 0
  EXPECT_NEAR(g.origin_m.z(), 0.0, 1e-15);
  double bottom = 0;
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) bottom += static_cast<double>(g.at(i, j, 0));
  EXPECT_NEAR(bottom * h * h, 0.0213 * 0.0171, 2 * (0.0213 + 0.0171) * h / 4);
  // every fraction in [0, 1], margin cells empty
  for (float f : g.value) {
    EXPECT_GE(f, 0.0f);
    EXPECT_LE(f, 1.0f);
  }
  EXPECT_EQ(g.at(0, 0, 0), 0.0f);
}

TEST(Voxelize, SphereVolumeConvergesWithResolution) {
  const double r = 0.02;
  const auto m = datasets::geodesic_sphere(40, r);
  const double Vmesh = volume_of(m);
  double prev = 1;
  for (double h : {4e-3, 2e-3, 1e-3}) {
    VoxelizeOptions vo;
    vo.h_m = h;
    vo.floor_at_mesh_bottom = false;
    const auto g = voxelize_fraction(m, vo);
    const double err = std::abs(grid_volume(g) - Vmesh) / Vmesh;
    std::printf("sphere r = 20 mm, h = %.1f mm: voxel volume error %.2e\n", h * 1e3, err);
    // sampling error bound: one sub-sample strip over the silhouette, 2πr·2r·(h/S)/V relative
    EXPECT_LT(err, 2 * std::numbers::pi * r * 2 * r * (h / 4) / Vmesh);
    prev = err;
  }
  EXPECT_LT(prev, 2e-3);
}

TEST(Voxelize, MoldBlocksWeigh250g) {
  for (auto mold : {datasets::Mold::kGiraffe, datasets::Mold::kShip}) {
    const auto m = datasets::mold_mesh(mold);
    VoxelizeOptions vo;
    vo.h_m = 2e-3;
    const auto g = voxelize_fraction(m, vo);
    const double mass = grid_volume(g) * constants::kIceDensity;
    std::printf("%s: voxelized mass %.2f g (mesh %.2f g)\n", datasets::mold_name(mold).c_str(), mass * 1e3,
                volume_of(m) * constants::kIceDensity * 1e3);
    // 1%: the outline's thin legs/masts are a few cells wide at h = 2 mm; sampling is S = 4
    EXPECT_NEAR(mass, 0.25, 0.0025);
  }
}

TEST(Voxelize, OccupancyThresholdsAtHalf) {
  const auto m = box(0.01, 0.01, 0.01, Eigen::Vector3d::Zero());
  VoxelizeOptions vo;
  vo.h_m = 1e-3;
  const auto occ = voxelize_occupancy(m, vo);
  long n = 0;
  for (auto v : occ.value) n += v;
  EXPECT_EQ(n, 1000);
}

TopologyReport check(const IndexedMesh& m) { return check_topology(TriMesh<double>::from_indexed(m)); }

TEST(Isosurface, VoxelizedSphereIsClosedManifoldWithRightVolume) {
  const double r = 0.02;
  const auto sphere = datasets::geodesic_sphere(40, r);
  VoxelizeOptions vo;
  vo.h_m = 1e-3;
  vo.floor_at_mesh_bottom = false;
  const auto g = voxelize_fraction(sphere, vo);
  const auto s = isosurface(g);
  const auto rep = check(s);
  EXPECT_TRUE(rep.valid()) << (rep.problems.empty() ? "" : rep.problems.front().describe());
  EXPECT_EQ(rep.counts.S, 1);
  EXPECT_EQ(rep.counts.G, 0);
  EXPECT_EQ(rep.counts.chi, 0);
  const double V = volume_of(s), Vm = volume_of(sphere);
  std::printf("isosurface of a 20 mm sphere at h = 1 mm: %zu triangles, volume error %.2e\n", s.F.size(),
              (V - Vm) / Vm);
  EXPECT_GT(V, 0) << "outward orientation gives a positive volume";
  // the 0.5 level of a cell-averaged indicator sits within ~h²/r of the true surface:
  // relative volume error ≲ 3 (h/r)² · few; 1.5% at r/h = 20
  EXPECT_NEAR(V, Vm, 0.015 * Vm);
}

TEST(Isosurface, TorusHasGenusOneAndBlockIsClosed) {
  const auto torus = datasets::torus(0.02, 0.008, 64, 32);
  VoxelizeOptions vo;
  vo.h_m = 1e-3;
  vo.floor_at_mesh_bottom = false;
  const auto rep = check(isosurface(voxelize_fraction(torus, vo)));
  EXPECT_TRUE(rep.valid());
  EXPECT_EQ(rep.counts.S, 1);
  EXPECT_EQ(rep.counts.G, 1);

  // a block resting on the grid floor (layer 0 full): padding closes the bottom
  const auto blk = box(0.01, 0.012, 0.006, Eigen::Vector3d::Zero());
  VoxelizeOptions vb;
  vb.h_m = 1e-3;
  const auto g = voxelize_fraction(blk, vb);
  const auto m = isosurface(g);
  const auto rb = check(m);
  EXPECT_TRUE(rb.valid());
  EXPECT_EQ(rb.counts.S, 1);
  EXPECT_EQ(rb.counts.G, 0);
}

TEST(Isosurface, RandomFieldsGiveClosedOrientedManifolds) {
  // Worst case for marching cubes' ambiguities; the Kuhn decomposition has none.
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int trial = 0; trial < 5; ++trial) {
    Grid3<float> g(9, 8, 7, 1.0, Eigen::Vector3d::Zero(), 0.0f);
    for (auto& v : g.value) v = u(rng);
    g.at(3, 3, 3) = 0.5f;  // a value exactly at the level
    const auto m = isosurface(g);
    const auto rep = check(m);
    EXPECT_TRUE(rep.valid()) << "trial " << trial << ": "
                             << (rep.problems.empty() ? "" : rep.problems.front().describe());
    EXPECT_EQ(rep.counts.chi, 0);
    EXPECT_GT(volume_of(m), 0);
  }
}

TEST(Isosurface, OfAMeltingBlockStaysClosed) {
  const auto blk = box(0.02, 0.016, 0.01, Eigen::Vector3d::Zero());
  VoxelizeOptions vb;
  vb.h_m = 2e-3;
  IceMeltParams p;
  p.lamp_irradiance_W_m2 = 300;
  EnthalpySolver solver(voxelize_fraction(blk, vb), p);
  for (int snap = 0; snap < 4; ++snap) {
    solver.advance(300.0);
    const auto m = isosurface(solver.ice_fraction());
    if (m.F.empty()) break;
    const auto rep = check(m);
    EXPECT_TRUE(rep.valid()) << "snapshot " << snap;
    // mesh volume tracks the solver's ice volume (level 0.5 of a diffuse field): 25% at h = 2 mm
    // on a body only 5-10 cells across
    EXPECT_NEAR(volume_of(m), solver.ice_volume_m3(), 0.25 * solver.ice_volume_m3()) << "snapshot " << snap;
  }
}

}  // namespace
}  // namespace meltlab::sim::physics
