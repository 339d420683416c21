// The deformation pass computes eight vertices (and the scatter eight triangles) at a time in
// SIMD lanes, moving data between records and lanes with shuffles. Two layers of tests:
//   1. the shuffles themselves (lanes.h) against index arithmetic;
//   2. deform() on melted meshes with dead slots, against an independent scalar evaluation of
//      Alg. 1 with three-component formulas, compared bitwise:
//      every lane must give exactly the scalar result, for float and double, every mode,
//      constant and spatial kl, vertex counts that are not a multiple of eight.

#include <meltlab/datasets/procedural.h>
#include <meltlab/sim/melt.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "lanes.h"
#include "triangle_kernels.h"

namespace meltlab::sim {
namespace {

template <class Real>
class Lanes8 : public ::testing::Test {};
using Reals = ::testing::Types<float, double>;
TYPED_TEST_SUITE(Lanes8, Reals);

// The short-edge test skips a triangle on a float key that must not exceed its shortest
// squared edge (double meshes round it down): below it by at most 2^-22 relative (two float
// roundings' worth), +inf above float's range (a key that skips: longer than any reach), exact
// for floats.
TEST(ShortEdgeKey, IsAFloatNoGreaterThanTheSquaredLength) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> mantissa(1.0, 2.0);
  std::uniform_int_distribution<int> exponent(-120, 120);
  for (int i = 0; i < 100000; ++i) {
    const double x = std::ldexp(mantissa(rng), exponent(rng));
    const float k = float_at_most(x);
    ASSERT_LE(static_cast<double>(k), x) << x;
    ASSERT_GE(static_cast<double>(k), x * (1.0 - 0x1p-22)) << x;
  }
  EXPECT_EQ(float_at_most(1e300), std::numeric_limits<float>::infinity());
  EXPECT_EQ(float_at_most(std::numeric_limits<double>::infinity()), std::numeric_limits<float>::infinity());
  EXPECT_EQ(float_at_most(0.0), 0.0f);
  EXPECT_EQ(float_at_most(0.3f), 0.3f);
}

TYPED_TEST(Lanes8, TransposeMovesElementIJToJI) {
  using Real = TypeParam;
  Lanes<Real> in[kLanes], out[kLanes];
  for (std::size_t i = 0; i < kLanes; ++i)
    for (std::size_t j = 0; j < kLanes; ++j) in[i][j] = static_cast<Real>(10 * i + j);
  transpose8<Real>(in, out);
  for (std::size_t i = 0; i < kLanes; ++i)
    for (std::size_t j = 0; j < kLanes; ++j) EXPECT_EQ(out[j][i], in[i][j]) << i << "," << j;
}

TYPED_TEST(Lanes8, InterleaveInvertsDeinterleave) {
  using Real = TypeParam;
  Real packed[3 * kLanes], back[3 * kLanes];
  for (std::size_t k = 0; k < 3 * kLanes; ++k) packed[k] = static_cast<Real>(k);
  Lanes<Real> x, y, z;
  deinterleave3<Real>(packed, x, y, z);
  for (std::size_t i = 0; i < kLanes; ++i) {
    EXPECT_EQ(x[i], packed[3 * i]);
    EXPECT_EQ(y[i], packed[3 * i + 1]);
    EXPECT_EQ(z[i], packed[3 * i + 2]);
  }
  interleave3<Real>(back, x, y, z);
  EXPECT_EQ(std::memcmp(back, packed, sizeof(packed)), 0);
}

// gather_xyz reads eight four-number records at scattered offsets into lanes, in record order.
TYPED_TEST(Lanes8, GatherXyzReadsRecordIIntoLaneI) {
  using Real = TypeParam;
  Real table[4 * 40];
  for (std::size_t k = 0; k < std::size(table); ++k) table[k] = static_cast<Real>(k);
  const std::uint32_t offset[kLanes] = {27, 0, 90, 3, 3, 150, 61, 12};  // repeats, any order, any alignment
  Lanes<Real> x, y, z;
  gather_xyz<Real>(table, offset, x, y, z);
  for (std::size_t i = 0; i < kLanes; ++i) {
    EXPECT_EQ(x[i], table[offset[i]]) << i;
    EXPECT_EQ(y[i], table[offset[i] + 1]) << i;
    EXPECT_EQ(z[i], table[offset[i] + 2]) << i;
  }
}

// The lane short-edge key is the scalar one lane by lane (a double rounded down to float; +inf
// above float's range; a float itself).
TYPED_TEST(Lanes8, ShortEdgeKeyEqualsScalar) {
  using Real = TypeParam;
  using Lim = std::numeric_limits<Real>;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> mantissa(1.0, 2.0);
  std::uniform_int_distribution<int> exponent(-140, 140);
  for (int round = 0; round < 2000; ++round) {
    Lanes<Real> x;
    for (std::size_t i = 0; i < kLanes; ++i) x[i] = static_cast<Real>(std::ldexp(mantissa(rng), exponent(rng)));
    if (round == 0) x[0] = 0, x[1] = Lim::max(), x[2] = Lim::infinity(), x[3] = Lim::denorm_min();
    const Lanes<float> key = lane_float_at_most<Real>(x);
    for (std::size_t i = 0; i < kLanes; ++i) {
      const float got = key[i], want = float_at_most(x[i]);
      ASSERT_EQ(std::memcmp(&got, &want, sizeof(float)), 0) << "x = " << x[i] << " lane " << i;
    }
  }
}

// The short-edge scan's candidates come from the bits of a comparison: bit i is lane i, and a
// NaN key (no comparison true) stays a candidate, as the scalar test keeps it.
TYPED_TEST(Lanes8, LaneBitsAreTheLanesOfAMask) {
  using Real = TypeParam;
  const Lanes<Real> x = broadcast<Real>(2);
  EXPECT_EQ(lane_bits<Real>(x > Real(1)), 0xffu);
  EXPECT_EQ(lane_bits<Real>(x > Real(2)), 0u);  // equal is not greater
  EXPECT_EQ(lane_bits<Real>(~(x > Real(2))), 0xffu);
  for (std::size_t i = 0; i < kLanes; ++i) {
    Lanes<Real> y = x;
    y[i] = Real(0.5);
    EXPECT_EQ(lane_bits<Real>(y > Real(1)), 0xffu & ~(1u << i)) << "lane " << i;
    EXPECT_EQ(lane_bits<Real>(~(y > Real(1))), 1u << i) << "lane " << i;
    y[i] = std::numeric_limits<Real>::quiet_NaN();
    EXPECT_EQ(lane_bits<Real>(~(y > Real(1))), 1u << i) << "NaN in lane " << i;
  }
  const std::uint8_t flags[kLanes] = {0, 1, 0, 0, 7, 0, 0, 255};
  EXPECT_EQ(lane_bits<Real>(lanes_nonzero<Real>(flags)), 0x92u);
}

// The scan's candidate list from a group's bits: every set bit's index, ascending, for all 256
// masks (the compress of AVX-512 and the loop elsewhere).
TEST(LaneBits, AppendBitIndicesListsEverySetBitAscending) {
  for (unsigned bits = 0; bits < 256; ++bits) {
    std::int32_t out[3 + kLanes] = {-7, -7, -7};
    std::vector<std::int32_t> want = {-7, -7, -7};
    for (std::int32_t i = 0; i < 8; ++i)
      if (bits & (1u << i)) want.push_back(1000 + i);
    const std::size_t n = append_bit_indices(bits, 1000, out + 3);
    ASSERT_EQ(n + 3, want.size()) << "bits " << bits;
    EXPECT_TRUE(std::equal(want.begin(), want.end(), out)) << "bits " << bits;
  }
}

// The lane 1/|v| is the scalar one, including zero, subnormal, huge and infinite |v|².
TYPED_TEST(Lanes8, InverseLengthEqualsScalar) {
  using Real = TypeParam;
  using Lim = std::numeric_limits<Real>;
  const Real cases[] = {0,          Lim::denorm_min(), Lim::min() / 4, Lim::min(),      Real(1e-7), Real(0.3),
                        1,          Real(7.5e6),       Lim::max(),     Lim::infinity(), Real(2),    Real(1) / 3,
                        Real(1e30), Real(4),           Real(9),        Real(0.01)};
  for (std::size_t base = 0; base < std::size(cases); base += kLanes) {
    Lanes<Real> n2;
    for (std::size_t i = 0; i < kLanes; ++i) n2[i] = cases[base + i];
    const Lanes<Real> inv = lane_inverse_length<Real>(n2);
    for (std::size_t i = 0; i < kLanes; ++i) {
      const Real x = n2[i];
      const Real expected = x > 0 ? Real(1) / std::sqrt(std::max(x, Lim::min())) : Real(0);
      EXPECT_EQ(inv[i], expected) << "n2 = " << x;
    }
  }
}

// ---- 2. deform() against a scalar evaluation --------------------------------------------

// 1/|v| as the deformation defines it (zero for a zero vector, |v|² clamped to the smallest
// normal number).
template <class Real>
Real reference_inverse_length(Real n2) {
  return n2 > 0 ? Real(1) / std::sqrt(std::max(n2, std::numeric_limits<Real>::min())) : Real(0);
}

// Alg. 1 one vertex and one triangle at a time: unit face normal (Eq. 2.9) and unit corner
// edges per live triangle, summed per vertex in ascending triangle order, then Eq. 2.10, 3.5,
// 3.6, 3.8 with three-component vectors (dot products summed left to right: Eigen's own
// dot() sums in an order that depends on the precision and the SIMD packets it uses).
template <class Real>
Real dot3(const Vec3<Real>& a, const Vec3<Real>& b) {
  return a.x() * b.x() + a.y() * b.y() + a.z() * b.z();
}

template <class Real>
TriMesh<Real> reference_deform(TriMesh<Real> m, const MeltParams& p, const KlField& kl) {
  using V = Vec3<Real>;
  const std::size_t nv = m.vertex_slots();
  std::vector<V> nsum(nv, V::Zero()), esum(nv, V::Zero());
  std::vector<Index> count(nv, 0);
  for (std::size_t t = 0; t < m.triangle_slots(); ++t) {
    if (!m.triangle_alive[t]) continue;
    V P[3];
    for (std::size_t k = 0; k < 3; ++k) P[k] = m.position[static_cast<std::size_t>(m.triangle[t][k])];
    const V ab = P[1] - P[0], ac = P[2] - P[0];
    const V n(ab.y() * ac.z() - ab.z() * ac.y(), ab.z() * ac.x() - ab.x() * ac.z(), ab.x() * ac.y() - ab.y() * ac.x());
    const V unit_n = n * reference_inverse_length(dot3(n, n));
    m.face_normal.set(t, unit_n);
    for (std::size_t k = 0; k < 3; ++k) {
      const V e = P[(k + 1) % 3] - P[k];
      const auto v = static_cast<std::size_t>(m.triangle[t][k]);
      nsum[v] += unit_n;
      esum[v] += e * reference_inverse_length(dot3(e, e));
      ++count[v];
    }
  }
  const Real kE = static_cast<Real>(p.kE), kN = static_cast<Real>(p.kN);
  for (std::size_t v = 0; v < nv; ++v) {
    if (!m.vertex_alive[v] || count[v] == 0) {
      m.normal.set(v, V::Zero());
      m.displacement.set(v, V::Zero());
      m.triangle_count[v] = count[v];
      continue;
    }
    const V N = nsum[v] * reference_inverse_length(dot3(nsum[v], nsum[v]));
    const V ME = p.edge_sum == EdgeSumMode::kMean ? V(esum[v] / static_cast<Real>(count[v])) : esum[v];
    const Real s = static_cast<Real>(p.kg * kl.value(m.position[v].template cast<double>()));
    const Real d = dot3(N, ME);
    const bool combined = p.tie == TieRule::kLessEqual ? d <= 0 : d < 0;
    V move = V::Zero();
    switch (p.deform) {
      case DeformMode::kCombined:
        move = combined ? V((kE * ME - kN * N) * s) : V((-kN * N) * s);
        break;
      case DeformMode::kNormalOnly:
        move = (-kN * N) * s;
        break;
      case DeformMode::kEdgeOnly:
        move = (kE * ME) * s;
        break;
    }
    m.normal.set(v, N);
    m.displacement.set(v, move);
    m.position.set(v, m.position[v] + move);
    m.triangle_count[v] = count[v];
  }
  return m;
}

template <class Real>
void expect_bitwise_equal(const Vec3Columns<Real>& got, const Vec3Columns<Real>& want, const char* what,
                          const std::string& where) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i)
    if (std::memcmp(got[i].data(), want[i].data(), 3 * sizeof(Real)) != 0) {
      ADD_FAILURE() << where << ": " << what << "[" << i << "] = " << got[i].transpose() << ", scalar "
                    << want[i].transpose();
      return;
    }
}

// A melted mesh with dead vertex and triangle slots (no compaction), odd slot counts.
template <class Real>
TriMesh<Real> melted_with_dead_slots(const IndexedMesh& input, int cycles) {
  MeltParams p = relative_melt_params(input, 0.1, 0.6);
  p.compact_below = 0.0;
  p.compact_after = 0.0;
  MeltSimulator<Real> sim(TriMesh<Real>::from_indexed(input), p, make_constant_kl(1.0));
  for (int c = 0; c < cycles; ++c) sim.step();
  return sim.mesh();
}

template <class Real>
class LaneMoves : public ::testing::Test {};
TYPED_TEST_SUITE(LaneMoves, Reals);

TYPED_TEST(LaneMoves, DeformEqualsScalarFormulasBitwise) {
  using Real = TypeParam;
  IndexedMesh sphere = datasets::geodesic_sphere(9, 1.0);  // 812 vertices: not a multiple of 8
  std::mt19937 rng(5);
  std::normal_distribution<double> jitter(0.0, 0.02);
  for (auto& v : sphere.V) v += Vec3<double>(jitter(rng), jitter(rng), jitter(rng));
  const TriMesh<Real> start = melted_with_dead_slots<Real>(sphere, 25);
  std::size_t dead = 0;
  for (auto a : start.vertex_alive) dead += a == 0;
  ASSERT_GT(dead, 0u) << "the test needs dead vertex slots";
  ASSERT_NE(start.vertex_slots() % kLanes, 0u) << "the test needs a partial group of eight";

  const auto field = make_point_source_kl(Vec3<double>(1, 0, 0), 0.2, 0.8, 0.5, Falloff::kGaussian);
  const auto constant = make_constant_kl(0.7);
  for (const KlField* kl : {static_cast<const KlField*>(constant.get()), static_cast<const KlField*>(field.get())})
    for (DeformMode mode : {DeformMode::kCombined, DeformMode::kNormalOnly, DeformMode::kEdgeOnly})
      for (TieRule tie : {TieRule::kLessEqual, TieRule::kStrict})
        for (EdgeSumMode sum : {EdgeSumMode::kMean, EdgeSumMode::kSum}) {
          MeltParams p = relative_melt_params(sphere, 0.1, 0.6, 0.9);
          p.deform = mode, p.tie = tie, p.edge_sum = sum;
          const std::string where = std::string(kl == field.get() ? "point-source kl" : "constant kl") + " mode " +
                                    std::to_string(static_cast<int>(mode)) + " tie " +
                                    std::to_string(static_cast<int>(tie)) + " sum " +
                                    std::to_string(static_cast<int>(sum));
          TriMesh<Real> got = start;
          deform(got, p, *kl);
          const TriMesh<Real> want = reference_deform(start, p, *kl);
          expect_bitwise_equal(got.position, want.position, "position", where);
          expect_bitwise_equal(got.normal, want.normal, "normal", where);
          expect_bitwise_equal(got.displacement, want.displacement, "displacement", where);
          for (std::size_t t = 0; t < got.triangle_slots(); ++t)
            if (got.triangle_alive[t]) {
              ASSERT_EQ(std::memcmp(got.face_normal[t].data(), want.face_normal[t].data(), 3 * sizeof(Real)), 0)
                  << where << ": face normal " << t;
            }
          EXPECT_EQ(got.triangle_count, want.triangle_count) << where;
          if (::testing::Test::HasFailure()) return;
        }
}

}  // namespace
}  // namespace meltlab::sim
