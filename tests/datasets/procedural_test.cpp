// Procedural shapes (procedural.h, mesh_transforms.h): topology, counts, orientation and
// geometry against closed forms.

#include <meltlab/datasets/mesh_transforms.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "mesh_checks.h"

namespace meltlab::datasets {
namespace {

using sim::EulerCounts;
using test::signed_volume;
using test::topology_of;

constexpr double kPi = std::numbers::pi;
// Positions are computed with a few floating-point operations from exact inputs: relative
// error of a handful of ulps.
constexpr double kRoundOff = 1e-12;

// Every triangle mesh a generator returns: closed, manifold, consistently oriented with
// valence >= 3, Euler-consistent, outward (positive volume), no duplicate or unused
// vertices, of the given genus and shell count.
void expect_closed_solid(const IndexedMesh& m, std::int64_t genus, std::int64_t shells = 1) {
  const auto r = topology_of(m);
  EXPECT_TRUE(r.valid()) << (r.problems.empty() ? "invalid" : r.problems.front().describe());
  EXPECT_EQ(r.counts.chi, 0);
  EXPECT_EQ(r.counts.G, genus);
  EXPECT_EQ(r.counts.S, shells);
  EXPECT_EQ(r.counts.V, static_cast<std::int64_t>(m.V.size())) << "every vertex is used";
  EXPECT_GT(signed_volume(m), 0.0) << "outward orientation";
  const auto welded = sim::weld_vertices(sim::to_polygon_mesh(m));
  EXPECT_EQ(welded.merged_vertices, 0u) << "no duplicate vertices";
}

void expect_counts(const EulerCounts& c, std::int64_t V, std::int64_t E, std::int64_t F, std::int64_t H, std::int64_t S,
                   std::int64_t G) {
  EXPECT_EQ(c.V, V);
  EXPECT_EQ(c.E, E);
  EXPECT_EQ(c.F, F);
  EXPECT_EQ(c.H, H);
  EXPECT_EQ(c.S, S);
  EXPECT_EQ(c.G, G);
  EXPECT_EQ(c.chi, 0);
  EXPECT_TRUE(c.genus_valid);
}

// ---------------------------------------------------------------- Tab. 2.3

struct Tab23Row {
  const char* name;
  PolygonMesh mesh;
  std::int64_t V, E, F, H, S, G;
};

std::vector<Tab23Row> tab_2_3() {
  return {
      {"cube of quads", cube_quads(), 8, 12, 6, 0, 1, 0},
      {"cube of triangles", sim::to_polygon_mesh(cube_triangles()), 8, 18, 12, 0, 1, 0},
      {"double cube", double_cube_quads(), 16, 24, 12, 0, 2, 0},
      {"cube with a hole in a face", cube_with_face_hole(), 16, 24, 11, 1, 1, 0},
      {"cube with a tunnel", cube_with_tunnel(), 16, 24, 10, 2, 1, 1},
      {"cube with a tunnel, front triangulated", cube_with_tunnel_front_triangulated(), 16, 32, 17, 1, 1, 1},
  };
}

TEST(Tab23, EulerCountsOfSimMatchTheTable) {
  for (const auto& row : tab_2_3()) {
    SCOPED_TRACE(row.name);
    expect_counts(sim::euler_counts(row.mesh), row.V, row.E, row.F, row.H, row.S, row.G);
    const auto r = sim::check_topology(row.mesh);
    EXPECT_TRUE(r.closed && r.manifold && r.oriented);
    EXPECT_EQ(r.low_valence_vertices, 0);
  }
}

// The same counts derived here independently of sim::check_topology, with the shells of a
// face's hole loops joined to the face.
TEST(Tab23, IndependentCountsMatchTheTable) {
  for (const auto& row : tab_2_3()) {
    SCOPED_TRACE(row.name);
    std::set<sim::Index> used;
    for (const auto& f : row.mesh.faces) {
      used.insert(f.outer.begin(), f.outer.end());
      for (const auto& h : f.holes) used.insert(h.begin(), h.end());
    }
    const auto V = static_cast<std::int64_t>(used.size());
    const std::int64_t E = test::edge_count(row.mesh);
    const auto F = static_cast<std::int64_t>(row.mesh.faces.size());
    const auto H = static_cast<std::int64_t>(row.mesh.hole_count());
    const std::int64_t S = test::shells_through_faces(row.mesh);
    EXPECT_EQ(V, row.V);
    EXPECT_EQ(E, row.E);
    EXPECT_EQ(F, row.F);
    EXPECT_EQ(H, row.H);
    EXPECT_EQ(S, row.S);
    // Eq. 2.3 with chi = 0 gives G = S - (V - E + F - H) / 2.
    EXPECT_EQ(S - (V - E + F - H) / 2, row.G);
  }
}

TEST(Tab23, HoleLoopsRunOppositeToTheirFace) {
  for (const auto& mesh : {cube_with_face_hole(), cube_with_tunnel(), cube_with_tunnel_front_triangulated()}) {
    for (const auto& f : mesh.faces) {
      auto newell = [&](const std::vector<sim::Index>& loop) {
        Eigen::Vector3d n = Eigen::Vector3d::Zero();
        for (std::size_t k = 0; k < loop.size(); ++k)
          n += mesh.V[static_cast<std::size_t>(loop[k])].cross(
              mesh.V[static_cast<std::size_t>(loop[(k + 1) % loop.size()])]);
        return n;
      };
      for (const auto& h : f.holes) EXPECT_LT(newell(f.outer).dot(newell(h)), 0.0);
    }
  }
}

TEST(Tab23, TriangulatedFormsKeepVerticesShellsGenusAndVolume) {
  const double e = 0.1;
  struct Case {
    PolygonMesh mesh;
    std::int64_t triangles, shells, genus;
    double volume;
  };
  const std::vector<Case> cases = {
      {cube_quads(e), 12, 1, 0, e * e * e},
      {double_cube_quads(e), 24, 2, 0, 2 * e * e * e},
      // pocket of (e/2)² x e/2
      {cube_with_face_hole(e), 28, 1, 0, e * e * e - 0.125 * e * e * e},
      // tunnel of (e/2)² x e
      {cube_with_tunnel(e), 32, 1, 1, e * e * e - 0.25 * e * e * e},
      {cube_with_tunnel_front_triangulated(e), 32, 1, 1, e * e * e - 0.25 * e * e * e},
  };
  for (const auto& c : cases) {
    const IndexedMesh t = triangulated_with_holes(c.mesh);
    EXPECT_EQ(static_cast<std::int64_t>(t.F.size()), c.triangles);
    EXPECT_EQ(t.V.size(), c.mesh.V.size());
    expect_closed_solid(t, c.genus, c.shells);
    EXPECT_NEAR(signed_volume(t), c.volume, kRoundOff * c.volume);
  }
}

TEST(Tab23, CubesHaveTheRequestedEdge) {
  const PolygonMesh q = cube_quads(2.5);
  for (const auto& p : q.V) EXPECT_EQ(p.cwiseAbs(), Eigen::Vector3d::Constant(1.25));
  EXPECT_NEAR(signed_volume(cube_triangles(2.5)), 2.5 * 2.5 * 2.5, kRoundOff);
  EXPECT_THROW(cube_quads(0.0), InputError);
  EXPECT_THROW(cube_with_tunnel(-1.0), InputError);
  EXPECT_THROW(cube_with_face_hole(std::nan("")), InputError);
}

// ---------------------------------------------------------------- subdivided cube, A

TEST(SubdividedCube, CountsVolumeAndSurface) {
  for (int n : {1, 2, 3, 4, 7}) {
    SCOPED_TRACE(n);
    const double edge = 0.3;
    const IndexedMesh m = subdivided_cube(n, edge);
    EXPECT_EQ(m.V.size(), static_cast<std::size_t>(6 * n * n + 2));
    EXPECT_EQ(m.F.size(), static_cast<std::size_t>(12 * n * n));
    expect_closed_solid(m, 0);
    EXPECT_NEAR(signed_volume(m), edge * edge * edge, kRoundOff);
    for (const auto& p : m.V) EXPECT_NEAR(p.cwiseAbs().maxCoeff(), edge / 2, kRoundOff) << "vertex off the cube";
  }
  EXPECT_THROW(subdivided_cube(0), InputError);
  EXPECT_THROW(subdivided_cube(2, -1.0), InputError);
}

TEST(BenchmarkObjects, HaveTheTriangleCountsOfTab51) {
  const IndexedMesh a = benchmark_object('A');
  EXPECT_EQ(a.F.size(), 192u);
  EXPECT_EQ(a.V.size(), 98u);
  expect_closed_solid(a, 0);
  const IndexedMesh b = benchmark_object('B');
  EXPECT_EQ(b.F.size(), 16000u);
  expect_closed_solid(b, 0);
  const IndexedMesh c = benchmark_object('c');
  EXPECT_EQ(c.F.size(), 32000u);
  expect_closed_solid(c, 0);
  for (const auto* m : {&b, &c})
    for (const auto& p : m->V) EXPECT_NEAR(p.norm(), 0.05, kRoundOff);
  EXPECT_THROW(benchmark_object('D'), InputError);
}

// ---------------------------------------------------------------- spheres

// Volume deficit of an inscribed latitude-longitude polyhedron: to leading order, a
// polygon of angular step d inscribed in a circle loses d²/6 of its area, once around the
// axis (d = 2 pi / segments) and once along the meridian (d = pi / rings). Allow 1.5x the
// leading-order sum for the higher-order terms (measured: 1.1x at 100 x 81, 0.75x at 8 x 4).
constexpr double kUvDeficitSafety = 1.5;

TEST(UvSphere, CountsAndVolumeWithinTheInscribedBound) {
  struct Case {
    int segments, rings;
  };
  for (const Case c : {Case{3, 2}, Case{8, 4}, Case{32, 16}, Case{100, 81}, Case{160, 101}}) {
    SCOPED_TRACE(::testing::Message() << c.segments << " x " << c.rings);
    const double r = 0.05;
    const IndexedMesh m = uv_sphere(c.segments, c.rings, r);
    EXPECT_EQ(m.F.size(), static_cast<std::size_t>(2 * c.segments * (c.rings - 1)));
    EXPECT_EQ(m.V.size(), static_cast<std::size_t>(c.segments * (c.rings - 1) + 2));
    expect_closed_solid(m, 0);
    for (const auto& p : m.V) EXPECT_NEAR(p.norm(), r, kRoundOff);
    const double exact = 4.0 / 3.0 * kPi * r * r * r;
    const double deficit = (exact - signed_volume(m)) / exact;
    const double d_phi = 2 * kPi / c.segments, d_theta = kPi / c.rings;
    EXPECT_GT(deficit, 0.0) << "an inscribed polyhedron lies inside the sphere";
    EXPECT_LT(deficit, kUvDeficitSafety * (d_phi * d_phi + d_theta * d_theta) / 6.0);
  }
  EXPECT_THROW(uv_sphere(2, 10), InputError);
  EXPECT_THROW(uv_sphere(10, 1), InputError);
  EXPECT_THROW(uv_sphere(10, 10, -1.0), InputError);
}

TEST(Icosphere, CountsOnTheSphereAndConvergesFromBelow) {
  double previous = 0.0;
  const double r = 2.0, exact = 4.0 / 3.0 * kPi * r * r * r;
  for (int k = 0; k <= 4; ++k) {
    SCOPED_TRACE(k);
    const IndexedMesh m = icosphere(k, r);
    const auto p4 = static_cast<std::size_t>(std::pow(4, k));
    EXPECT_EQ(m.F.size(), 20 * p4);
    EXPECT_EQ(m.V.size(), 10 * p4 + 2);
    expect_closed_solid(m, 0);
    for (const auto& p : m.V) EXPECT_NEAR(p.norm(), r, kRoundOff * r);
    const double v = signed_volume(m);
    EXPECT_LT(v, exact);
    EXPECT_GT(v, previous) << "refining adds volume";
    previous = v;
  }
  EXPECT_THROW(icosphere(-1), InputError);
  EXPECT_THROW(icosphere(10), InputError);
}

TEST(SphereWithTriangles, HasExactlyTheRequestedCount) {
  for (int t : {6, 8, 320, 1000, 16000, 32000, 15998}) {
    SCOPED_TRACE(t);
    const IndexedMesh m = sphere_with_triangles(t, 0.5);
    EXPECT_EQ(m.F.size(), static_cast<std::size_t>(t));
    expect_closed_solid(m, 0);
  }
  EXPECT_THROW(sphere_with_triangles(16001), InputError) << "odd: no closed triangle mesh";
  EXPECT_THROW(sphere_with_triangles(4), InputError);
}

// ---------------------------------------------------------------- cylinder

TEST(Cylinder, ClosedSolidWithThePrismVolume) {
  const double r = 0.025, h = 0.08;
  const int n = 48;
  const IndexedMesh m = cylinder(r, h, n);
  EXPECT_EQ(m.V.size(), static_cast<std::size_t>(2 * n + 2));
  EXPECT_EQ(m.F.size(), static_cast<std::size_t>(4 * n));
  expect_closed_solid(m, 0);
  // The inscribed prism: n triangles of area r² sin(2π/n) / 2, times the height. Exact up to
  // round-off (1e-12 relative: a few hundred terms of about 1e-6 m³).
  const double prism = 0.5 * n * r * r * std::sin(2 * kPi / n) * h;
  EXPECT_NEAR(signed_volume(m), prism, 1e-12 * prism);
  EXPECT_THROW(cylinder(0.0, h, n), InputError);
  EXPECT_THROW(cylinder(r, h, 2), InputError);
}

// ---------------------------------------------------------------- torus

TEST(Torus, GenusOneAndVolumeWithinTheInscribedBound) {
  const double R = 0.03, r = 0.01;
  const int nu = 48, nv = 24;
  const IndexedMesh m = torus(R, r, nu, nv);
  EXPECT_EQ(m.V.size(), static_cast<std::size_t>(nu * nv));
  EXPECT_EQ(m.F.size(), static_cast<std::size_t>(2 * nu * nv));
  expect_closed_solid(m, 1);
  // Pappus: 2 pi R · pi r². Same leading-order deficit argument as for the uv sphere.
  const double exact = 2 * kPi * kPi * R * r * r;
  const double deficit = (exact - signed_volume(m)) / exact;
  const double du = 2 * kPi / nu, dv = 2 * kPi / nv;
  EXPECT_GT(deficit, 0.0);
  EXPECT_LT(deficit, kUvDeficitSafety * (du * du + dv * dv) / 6.0);
  EXPECT_THROW(torus(0.01, 0.03, 8, 8), InputError);
  EXPECT_THROW(torus(0.03, 0.01, 2, 8), InputError);
  EXPECT_THROW(torus(0.03, 0.0, 8, 8), InputError);
}

// ---------------------------------------------------------------- dumbbell

TEST(Dumbbell, OneGenusZeroShellWithAResolvedThinNeck) {
  const DumbbellOptions o;
  const IndexedMesh m = dumbbell(o);
  expect_closed_solid(m, 0, 1);
  EXPECT_GE(m.F.size(), 2000u);
  EXPECT_LE(m.F.size(), 6000u);

  Eigen::Vector3d lo = m.V.front(), hi = m.V.front();
  for (const auto& p : m.V) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double length = 4 * o.ball_radius_m + o.ball_gap_m;
  EXPECT_NEAR(hi.x() - lo.x(), length, kRoundOff);
  EXPECT_NEAR(hi.x(), -lo.x(), kRoundOff) << "centred";
  EXPECT_LT(o.neck_radius_m / o.ball_radius_m, 0.25) << "neck well below the ball radius";

  // The straight neck: where the fillets end, x = +-(a - sqrt((R + rf)² - (rn + rf)²)).
  const double R = o.ball_radius_m, rn = o.neck_radius_m, rf = o.fillet_radius_m;
  const double a = R + o.ball_gap_m / 2;
  const double neck_half = a - std::sqrt((R + rf) * (R + rf) - (rn + rf) * (rn + rf));
  std::set<double> neck_rings;
  double min_radius = 1.0;
  for (const auto& p : m.V) {
    const double rho = std::hypot(p.y(), p.z());
    if (std::abs(p.x()) < neck_half) {
      EXPECT_NEAR(rho, rn, kRoundOff) << "neck vertex off the neck cylinder";
      neck_rings.insert(p.x());
    }
    if (std::abs(p.x()) < a) min_radius = std::min(min_radius, rho);
  }
  EXPECT_GE(neck_rings.size(), 5u) << "the neck is resolved by several vertex rings";
  EXPECT_NEAR(min_radius, rn, kRoundOff) << "the neck is the thinnest part between the balls";

  // Roughly uniform triangle size: rings are spaced by the edge length along the profile and
  // hold round(2 pi rho / edge) vertices, so every edge is between about half and twice the
  // target (the stitching diagonals across staggered rings are the longest: 1.75x measured).
  for (double e : test::edge_lengths(m)) {
    EXPECT_GT(e, 0.5 * o.edge_length_m);
    EXPECT_LT(e, 2.0 * o.edge_length_m);
  }

  // Volume: the solid contains the two balls and the neck cylinder between them, and lies in
  // the two balls plus a cylinder of ball radius between their centres. The mesh is
  // inscribed; its deficit is below (2 pi / ring vertices)² / 6 ~ 0.4 % on the balls.
  constexpr double kInscribedDeficit = 0.01;
  const double ball = 4.0 / 3.0 * kPi * R * R * R;
  const double lower = 2 * ball + kPi * rn * rn * o.ball_gap_m;
  const double upper = 2 * ball + kPi * R * R * 2 * a;
  EXPECT_GT(signed_volume(m), (1 - kInscribedDeficit) * lower);
  EXPECT_LT(signed_volume(m), upper);
}

TEST(Dumbbell, RefusesImpossibleShapes) {
  DumbbellOptions fat;
  fat.neck_radius_m = fat.ball_radius_m;
  EXPECT_THROW(dumbbell(fat), InputError);
  DumbbellOptions no_room;
  no_room.ball_gap_m = 0.001;
  no_room.fillet_radius_m = 0.01;
  EXPECT_THROW(dumbbell(no_room), InputError);
  DumbbellOptions coarse;
  coarse.edge_length_m = 0.05;
  EXPECT_THROW(dumbbell(coarse), InputError);
  DumbbellOptions zero;
  zero.edge_length_m = 0.0;
  EXPECT_THROW(dumbbell(zero), InputError);
}

TEST(Dumbbell, OtherProportionsStayValid) {
  DumbbellOptions o;
  o.ball_radius_m = 0.03;
  o.neck_radius_m = 0.002;
  o.ball_gap_m = 0.05;
  o.fillet_radius_m = 0.003;
  o.edge_length_m = 0.004;
  expect_closed_solid(dumbbell(o), 0, 1);
}

// ---------------------------------------------------------------- transforms

TEST(MeshTransforms, ScaleTranslateMerge) {
  const IndexedMesh s = icosphere(2, 1.0);
  const double v = signed_volume(s);
  EXPECT_NEAR(signed_volume(scaled(s, 2.0)), 8.0 * v, kRoundOff * 8.0 * v);
  const IndexedMesh t = translated(s, Eigen::Vector3d(5, 0, 0));
  EXPECT_NEAR(signed_volume(t), v, kRoundOff * v) << "volume is translation invariant on a closed mesh";
  const IndexedMesh two = merged(s, t);
  expect_closed_solid(two, 0, 2);
  EXPECT_THROW(scaled(s, -1.0), InputError) << "would turn the solid inside out";
  EXPECT_THROW(translated(s, Eigen::Vector3d(std::nan(""), 0, 0)), InputError);
  const PolygonMesh q = merged(cube_quads(), translated(scaled(cube_quads(), 0.5), Eigen::Vector3d(3, 0, 0)));
  expect_counts(sim::euler_counts(q), 16, 24, 12, 0, 2, 0);
}

TEST(MeshTransforms, TriangulatedWithHolesRefusesBadFaces) {
  PolygonMesh bent = cube_quads();
  bent.V[7] += Eigen::Vector3d(0, 0, 0.1);  // corner of three faces leaves their planes
  EXPECT_THROW(triangulated_with_holes(bent), InputError);
  PolygonMesh flat;
  flat.V = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  flat.faces.push_back({{0, 1, 2, 3}, {}});
  EXPECT_THROW(triangulated_with_holes(flat), InputError);
}

}  // namespace
}  // namespace meltlab::datasets

namespace meltlab::datasets {
namespace {
TEST(GeodesicSphere, CountsOrientationAndUniformity) {
  for (int f : {1, 2, 7, 40}) {
    const auto m = geodesic_sphere(f, 2.0);
    EXPECT_EQ(m.F.size(), static_cast<std::size_t>(20 * f * f));
    EXPECT_EQ(m.V.size(), static_cast<std::size_t>(10 * f * f + 2));
    const auto topo = sim::check_topology(sim::TriMesh<double>::from_indexed(m));
    EXPECT_TRUE(topo.valid());
    EXPECT_EQ(topo.counts.G, 0);
    const auto q = sim::mesh_quality(sim::TriMesh<double>::from_indexed(m));
    EXPECT_GT(q.volume, 0.0) << "outward";
    // Inscribed in the sphere: below 4/3 pi r^3, and converging to it (f = 40: -0.03%).
    EXPECT_LT(q.volume, 4.0 / 3.0 * M_PI * 8.0);
    if (f == 40) {
      EXPECT_NEAR(q.volume / (4.0 / 3.0 * M_PI * 8.0), 1.0, 1e-3);
    }
    if (f >= 7) {
      EXPECT_GT(q.min_q, 0.8) << "nearly equilateral everywhere";
    }
  }
  EXPECT_THROW(geodesic_sphere(0), InputError);
}
}  // namespace
}  // namespace meltlab::datasets
