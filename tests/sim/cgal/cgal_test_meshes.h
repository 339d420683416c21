#pragma once
// Meshes for the CGAL validator and repair tests, on top of tests/support/hand_meshes.h:
// a subdivided sphere, a cube of quads (as read from a file) and soup edits.

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/polygon_mesh.h>

#include <algorithm>
#include <map>
#include <utility>

#include "hand_meshes.h"

namespace meltlab::test {

/// Icosahedron subdivided `levels` times (each triangle into 4), vertices projected onto
/// the sphere of radius `r` about the origin: 20·4^levels triangles, CCW from outside.
inline IndexedMesh icosphere(int levels, double r = 1.0) {
  IndexedMesh m = icosahedron();
  for (auto& p : m.V) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<sim::Index, sim::Index>, sim::Index> midpoint;
    auto mid = [&](sim::Index a, sim::Index b) {
      const auto key = std::minmax(a, b);
      auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      const auto k = static_cast<sim::Index>(m.V.size());
      m.V.push_back((m.V[static_cast<std::size_t>(a)] + m.V[static_cast<std::size_t>(b)]).normalized());
      midpoint.emplace(key, k);
      return k;
    };
    std::vector<sim::Triangle> F;
    F.reserve(4 * m.F.size());
    for (const auto& t : m.F) {
      const sim::Index ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      F.push_back({t[0], ab, ca});
      F.push_back({t[1], bc, ab});
      F.push_back({t[2], ca, bc});
      F.push_back({ab, bc, ca});
    }
    m.F = std::move(F);
  }
  for (auto& p : m.V) p *= r;
  return m;
}

/// Signed volume enclosed by a closed triangle mesh (divergence theorem), positive for
/// outward orientation.
inline double signed_volume(const IndexedMesh& m) {
  double six_v = 0;
  for (const auto& t : m.F) {
    const V3& a = m.V[static_cast<std::size_t>(t[0])];
    const V3& b = m.V[static_cast<std::size_t>(t[1])];
    const V3& c = m.V[static_cast<std::size_t>(t[2])];
    six_v += a.x() * (b.y() * c.z() - b.z() * c.y()) - a.y() * (b.x() * c.z() - b.z() * c.x()) +
             a.z() * (b.x() * c.y() - b.y() * c.x());
  }
  return six_v / 6.0;
}

/// Unit cube [0,1]³ as 6 quads, CCW from outside; vertex k = (k&1, k>>1&1, k>>2&1).
/// Faces in the order -z, +z, -y, +y, -x, +x.
inline sim::PolygonMesh quad_cube(const V3& offset = V3::Zero()) {
  sim::PolygonMesh m;
  for (int k = 0; k < 8; ++k) m.V.push_back(V3(k & 1, (k >> 1) & 1, (k >> 2) & 1) + offset);
  m.faces = {{{0, 2, 3, 1}, {}}, {{4, 5, 7, 6}, {}}, {{0, 1, 5, 4}, {}},
             {{2, 6, 7, 3}, {}}, {{0, 4, 6, 2}, {}}, {{1, 3, 7, 5}, {}}};
  return m;
}

/// Appends the polygons of `b` to `a` (vertices not shared).
inline sim::PolygonMesh polygon_union(sim::PolygonMesh a, const sim::PolygonMesh& b) {
  const auto off = static_cast<sim::Index>(a.V.size());
  a.V.insert(a.V.end(), b.V.begin(), b.V.end());
  for (auto f : b.faces) {
    for (auto& v : f.outer) v += off;
    a.faces.push_back(std::move(f));
  }
  return a;
}

/// Reverses the vertex order of face `f`.
inline sim::PolygonMesh with_face_flipped(sim::PolygonMesh m, std::size_t f) {
  std::reverse(m.faces[f].outer.begin(), m.faces[f].outer.end());
  return m;
}

}  // namespace meltlab::test
