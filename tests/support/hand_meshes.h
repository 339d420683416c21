#pragma once
// Tiny hand-built meshes with known answers, shared by the sim tests. Larger shapes come
// from meltlab_datasets (procedural.h).

#include <meltlab/sim/mesh.h>

#include <cmath>
#include <vector>

namespace meltlab::test {

using sim::IndexedMesh;
using V3 = sim::Vec3<double>;

/// The monograph's tetrahedron unit test (Fig. 2.13): A(-1,0,1), B(0,0,-1), C(1,0,1),
/// D(0,1,0); triangles (D,B,A), (D,C,B), (D,A,C), (B,C,A).
inline IndexedMesh tetrahedron_fig_2_13() {
  IndexedMesh m;
  m.V = {V3(-1, 0, 1), V3(0, 0, -1), V3(1, 0, 1), V3(0, 1, 0)};
  const sim::Index A = 0, B = 1, C = 2, D = 3;
  m.F = {{D, B, A}, {D, C, B}, {D, A, C}, {B, C, A}};
  return m;
}

/// Regular octahedron with vertices at ±r on the axes: 0:+x 1:-x 2:+y 3:-y 4:+z 5:-z.
inline IndexedMesh octahedron(double r = 1.0) {
  IndexedMesh m;
  m.V = {V3(r, 0, 0), V3(-r, 0, 0), V3(0, r, 0), V3(0, -r, 0), V3(0, 0, r), V3(0, 0, -r)};
  m.F = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

/// Unit cube [0,1]³ of 12 triangles, CCW from outside.
inline IndexedMesh cube12() {
  IndexedMesh m;
  for (int k = 0; k < 8; ++k) m.V.push_back(V3(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  m.F = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
         {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

/// Appends `b` to `a` as a separate part (indices shifted).
inline IndexedMesh disjoint_union(IndexedMesh a, const IndexedMesh& b) {
  const auto off = static_cast<sim::Index>(a.V.size());
  a.V.insert(a.V.end(), b.V.begin(), b.V.end());
  for (const auto& t : b.F) a.F.push_back({t[0] + off, t[1] + off, t[2] + off});
  return a;
}

/// `m` with vertex v renumbered new_index[v] (a permutation), the faces following.
inline IndexedMesh renumbered(const IndexedMesh& m, const std::vector<sim::Index>& new_index) {
  IndexedMesh out;
  out.V.resize(m.V.size());
  for (std::size_t v = 0; v < m.V.size(); ++v) out.V[static_cast<std::size_t>(new_index[v])] = m.V[v];
  for (const auto& f : m.F)
    out.F.push_back({new_index[static_cast<std::size_t>(f[0])], new_index[static_cast<std::size_t>(f[1])],
                     new_index[static_cast<std::size_t>(f[2])]});
  return out;
}

/// Moves every vertex of `m` by `d`.
inline IndexedMesh translated(IndexedMesh m, const V3& d) {
  for (auto& p : m.V) p += d;
  return m;
}

}  // namespace meltlab::test

namespace meltlab::test {

/// Regular icosahedron (12 vertices, 20 faces) with circumradius sqrt(1 + phi²).
inline IndexedMesh icosahedron() {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  IndexedMesh m;
  m.V = {V3(-1, p, 0),  V3(1, p, 0),  V3(-1, -p, 0), V3(1, -p, 0), V3(0, -1, p),  V3(0, 1, p),
         V3(0, -1, -p), V3(0, 1, -p), V3(p, 0, -1),  V3(p, 0, 1),  V3(-p, 0, -1), V3(-p, 0, 1)};
  m.F = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
         {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
         {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  return m;
}

}  // namespace meltlab::test
