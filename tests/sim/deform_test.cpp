#include <meltlab/core/error.h>
#include <meltlab/sim/melt.h>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

using V3 = Vec3<double>;
// Closed forms below are evaluated with a handful of double operations.
constexpr double kExact = 1e-12;

MeltParams params(double kE, double kN, double kg = 1.0) {
  MeltParams p;
  p.kE = kE;
  p.kN = kN;
  p.kg = kg;
  return p;
}

// Octahedron vertex (r,0,0): the four unit edges (-1,±1,0)/√2, (-1,0,±1)/√2 average to
// M_E = (-1/√2, 0, 0); N = (1,0,0). Convex: move = (kE·M_E - kN·N)·kg·kl = -(kE/√2 + kN)·s along x.
TEST(Deform, OctahedronClosedForm) {
  auto m = TriMesh<double>::from_indexed(test::octahedron(1.0));
  const double kE = 0.01, kN = 0.0001, kg = 0.5, kl = 0.8;
  deform(m, params(kE, kN, kg), *make_constant_kl(kl));
  const double step = (kE / std::sqrt(2.0) + kN) * kg * kl;
  for (std::size_t v = 0; v < 6; ++v) {
    EXPECT_NEAR(m.position[v].norm(), 1.0 - step, kExact) << "v" << v;
    EXPECT_NEAR(m.displacement[v].norm(), step, kExact);
    EXPECT_NEAR(m.normal[v].norm(), 1.0, kExact);
    EXPECT_EQ(m.triangle_count[v], 4);
  }
  EXPECT_NEAR(m.normal[0].x(), 1.0, kExact);
  for (std::size_t t = 0; t < 8; ++t) EXPECT_NEAR(m.face_normal[t].norm(), 1.0, kExact);
}

// A dimple: the +z apex pushed below the plane of its four neighbours. Its unit edges lean
// up (M_E along +z) while N is +z, so N·M_E > 0 and only the normal term acts: -kN·s·N.
TEST(Deform, ConcaveVertexUsesNormalTermOnly) {
  auto mesh = test::octahedron(1.0);
  mesh.V[4] = V3(0, 0, -0.2);
  auto m = TriMesh<double>::from_indexed(mesh);
  const double kE = 0.01, kN = 0.0001;
  deform(m, params(kE, kN), *make_constant_kl(1.0));
  EXPECT_NEAR(m.normal[4].z(), 1.0, kExact);
  EXPECT_NEAR(m.position[4].x(), 0.0, kExact);
  EXPECT_NEAR(m.position[4].z(), -0.2 - kN, kExact);
}

TEST(Deform, SingleVectorVariants) {
  const double kE = 0.01, kN = 0.001;
  auto normal_only = TriMesh<double>::from_indexed(test::octahedron(1.0));
  auto p = params(kE, kN);
  p.deform = DeformMode::kNormalOnly;
  deform(normal_only, p, *make_constant_kl(1.0));
  EXPECT_NEAR(normal_only.position[0].x(), 1.0 - kN, kExact);
  auto edge_only = TriMesh<double>::from_indexed(test::octahedron(1.0));
  p.deform = DeformMode::kEdgeOnly;
  deform(edge_only, p, *make_constant_kl(1.0));
  EXPECT_NEAR(edge_only.position[0].x(), 1.0 - kE / std::sqrt(2.0), kExact);
  // Eq. 3.5's second form: the sum of the 4 unit edges instead of their mean.
  auto summed = TriMesh<double>::from_indexed(test::octahedron(1.0));
  p.edge_sum = EdgeSumMode::kSum;
  deform(summed, p, *make_constant_kl(1.0));
  EXPECT_NEAR(summed.position[0].x(), 1.0 - 4.0 * kE / std::sqrt(2.0), kExact);
}

// Alg. 1's branches are Eq. 3.6 + 3.8, written independently here from the one-ring
// (unique neighbours, not the "next corner" trick) on a randomly perturbed mesh.
TEST(Deform, Algorithm1EqualsEquations36And38) {
  std::mt19937 rng(11);
  std::normal_distribution<double> jitter(0.0, 0.15);
  for (int trial = 0; trial < 20; ++trial) {
    auto mesh = test::disjoint_union(test::octahedron(1.0), test::translated(test::cube12(), {3, 0, 0}));
    for (auto& p : mesh.V) p += V3(jitter(rng), jitter(rng), jitter(rng));
    const double kE = 0.02, kN = 0.0002, kg = 0.7;
    std::map<Index, std::set<Index>> ring;
    std::map<Index, V3> normal_sum;
    for (const auto& t : mesh.F) {
      const V3 n = (mesh.V[static_cast<std::size_t>(t[1])] - mesh.V[static_cast<std::size_t>(t[0])])
                       .cross(mesh.V[static_cast<std::size_t>(t[2])] - mesh.V[static_cast<std::size_t>(t[0])])
                       .normalized();
      for (int k = 0; k < 3; ++k) {
        auto [it, fresh] = normal_sum.try_emplace(t[static_cast<std::size_t>(k)], V3::Zero());
        it->second += n;
      }
      for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j)
          if (j != k) ring[t[static_cast<std::size_t>(k)]].insert(t[static_cast<std::size_t>(j)]);
    }
    auto m = TriMesh<double>::from_indexed(mesh);
    deform(m, params(kE, kN, kg), *make_constant_kl(1.0));
    for (const auto& [v, nbrs] : ring) {
      const V3& P = mesh.V[static_cast<std::size_t>(v)];
      V3 ME = V3::Zero();
      for (Index s : nbrs) ME += (mesh.V[static_cast<std::size_t>(s)] - P).normalized();
      ME /= static_cast<double>(nbrs.size());
      const V3 MN = -normal_sum[v].normalized();
      const V3 M = MN.dot(ME) > 0 ? V3(kE * ME + kN * MN) : V3(kN * MN);  // Eq. 3.6
      const V3 expected = P + kg * 1.0 * M;                               // Eq. 3.8
      EXPECT_NEAR((m.position[static_cast<std::size_t>(v)] - expected).norm(), 0.0, kExact)
          << "trial " << trial << " v" << v;
    }
  }
}

// The tie N·M_E = 0: Alg. 1 (<=) takes the combined branch, Eq. 3.6 (strict) does not.
// A vertex in a flat fan with uneven angles has N = +z exactly and a non-zero M_E in the
// plane (every edge has z = 0 exactly), so N·M_E = 0 exactly.
TEST(Deform, TieRule) {
  const double angles_deg[] = {0, 40, 120, 180, 250, 300};
  IndexedMesh m;
  m.V.push_back(V3(0, 0, 0));  // centre
  for (double a : angles_deg) m.V.push_back(V3(std::cos(a * M_PI / 180), std::sin(a * M_PI / 180), 0));
  m.V.push_back(V3(0, 0, -1));  // apex below closes the solid
  for (int k = 0; k < 6; ++k) {
    const Index a = 1 + k, b = 1 + (k + 1) % 6;
    m.F.push_back({0, a, b});
    m.F.push_back({b, a, 7});
  }
  V3 me = V3::Zero();
  for (int k = 1; k <= 6; ++k) me += m.V[static_cast<std::size_t>(k)].normalized() / 6.0;
  ASSERT_GT(me.norm(), 0.05);
  const double kE = 0.1, kN = 0.001;
  auto p = params(kE, kN);
  auto le = TriMesh<double>::from_indexed(m);
  p.tie = TieRule::kLessEqual;
  deform(le, p, *make_constant_kl(1.0));
  auto strict = TriMesh<double>::from_indexed(m);
  p.tie = TieRule::kStrict;
  deform(strict, p, *make_constant_kl(1.0));
  EXPECT_NEAR((le.position[0] - (kE * me - kN * V3(0, 0, 1))).norm(), 0.0, kExact) << "Alg. 1: combined branch";
  EXPECT_NEAR((strict.position[0] - (-kN * V3(0, 0, 1))).norm(), 0.0, kExact) << "Eq. 3.6: normal branch";
}

TEST(Deform, LocalCoefficientScalesTheMove) {
  auto near = TriMesh<double>::from_indexed(test::octahedron(1.0));
  const auto field = make_point_source_kl(V3(1, 0, 0), 0.1, 0.9, 0.5, Falloff::kGaussian);
  deform(near, params(0.01, 0.0001), *field);
  const double d0 = near.displacement[0].norm();  // vertex at the source: kl = 1
  const double d1 = near.displacement[1].norm();  // opposite vertex: kl = 0.1 + 0.9 e^{-8}
  EXPECT_NEAR(d1 / d0, field->value(V3(-1, 0, 0)) / field->value(V3(1, 0, 0)), kExact);
}

TEST(Deform, ZeroKgDoesNotMove) {
  auto m = TriMesh<double>::from_indexed(test::octahedron(1.0));
  const auto before = m.position;
  deform(m, params(0.1, 0.01, 0.0), *make_constant_kl(1.0));
  EXPECT_EQ(m.position, before);
}

TEST(Deform, DegenerateTriangleContributesNoNaN) {
  auto mesh = test::octahedron(1.0);
  mesh.V[4] = V3(0, 0, 0);  // the +z apex on the equator plane: its 4 faces are flat
  mesh.V[2] = V3(0, 0, 0);  // and +y on the same point: two faces degenerate
  auto m = TriMesh<double>::from_indexed(mesh);
  deform(m, params(0.01, 0.001), *make_constant_kl(1.0));
  for (const auto& p : m.position) EXPECT_TRUE(p.allFinite());
}

TEST(Deform, InvalidParametersAreRefused) {
  auto m = TriMesh<double>::from_indexed(test::octahedron(1.0));
  EXPECT_THROW(deform(m, params(0.1, 0.01, 1.5), *make_constant_kl(1.0)), InputError);
  EXPECT_THROW(deform(m, params(std::nan(""), 0.01), *make_constant_kl(1.0)), InputError);
  EXPECT_THROW(deform(m, params(-0.1, 0.01), *make_constant_kl(1.0)), InputError);
}

}  // namespace
}  // namespace meltlab::sim
