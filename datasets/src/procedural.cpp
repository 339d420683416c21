// Procedural closed solids (procedural.h). Orientation rule used throughout: a face loop is
// counter-clockwise seen from outside, i.e. (b - a) x (c - a) points out of the solid.

#include <meltlab/datasets/mesh_transforms.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <map>
#include <unordered_map>
#include <vector>

#include "checks.h"

namespace meltlab::datasets {

using sim::Index;
using sim::PolygonFace;
using sim::Triangle;
using sim::Vec3;

namespace {

constexpr double kPi = std::numbers::pi;

// ---- cube corners: index = x + 2y + 4z (bits), centred on the origin ----

Vec3<double> cube_corner(int bits, double edge) {
  return {((bits & 1) ? 0.5 : -0.5) * edge, ((bits & 2) ? 0.5 : -0.5) * edge, ((bits & 4) ? 0.5 : -0.5) * edge};
}

// The six faces of the corner numbering above, each CCW seen from outside.
constexpr std::array<std::array<Index, 4>, 6> kCubeFaces = {{
    {0, 2, 3, 1},  // -z
    {4, 5, 7, 6},  // +z
    {0, 1, 5, 4},  // -y (front)
    {2, 6, 7, 3},  // +y (back)
    {0, 4, 6, 2},  // -x
    {1, 3, 7, 5},  // +x
}};
constexpr std::size_t kTopFace = 1;
constexpr std::size_t kFrontFace = 2;
constexpr std::size_t kBackFace = 3;

PolygonMesh cube_polygons(double edge) {
  PolygonMesh m;
  for (int b = 0; b < 8; ++b) m.V.push_back(cube_corner(b, edge));
  for (const auto& f : kCubeFaces) m.faces.push_back(PolygonFace{{f.begin(), f.end()}, {}});
  return m;
}

Index add_vertex(std::vector<Vec3<double>>& V, const Vec3<double>& p) {
  V.push_back(p);
  return static_cast<Index>(V.size() - 1);
}

// ---- surfaces of revolution about the z axis ----
//
// Vertex ring k (1 <= k <= n-1) has counts[k] vertices at height z[k], radius rho[k] and
// angles 2 pi (offset[k] + j / counts[k]); k = 0 and k = n are the poles (rho = 0).
// Neighbouring rings are stitched by merging their angle sequences, so rings may have
// different vertex counts: the band between rings with a and b vertices gets a + b
// triangles. Going up (+z) and around (+phi) is CCW seen from outside.
struct RevolutionProfile {
  std::vector<double> z;       // n + 1 heights, z[0] bottom pole, z[n] top pole
  std::vector<double> rho;     // n + 1 radii (rho[0], rho[n] ignored)
  std::vector<int> counts;     // vertices per ring (counts[0], counts[n] ignored)
  std::vector<double> offset;  // ring rotation, in turns (offset[0], offset[n] ignored)
};

IndexedMesh revolved_surface(const RevolutionProfile& p) {
  const std::size_t n = p.z.size() - 1;
  IndexedMesh m;
  std::vector<Index> first(n + 1, 0);
  first[0] = add_vertex(m.V, {0.0, 0.0, p.z[0]});
  for (std::size_t k = 1; k < n; ++k) {
    first[k] = static_cast<Index>(m.V.size());
    const int c = p.counts[k];
    for (int j = 0; j < c; ++j) {
      const double phi = 2.0 * kPi * (p.offset[k] + static_cast<double>(j) / c);
      m.V.emplace_back(p.rho[k] * std::cos(phi), p.rho[k] * std::sin(phi), p.z[k]);
    }
  }
  first[n] = add_vertex(m.V, {0.0, 0.0, p.z[n]});

  // Bottom fan: (pole, R_{j+1}, R_j) faces down.
  {
    const int c = p.counts[1];
    for (int j = 0; j < c; ++j) m.F.push_back({first[0], first[1] + (j + 1) % c, first[1] + j});
  }
  // Bands between ring k (A, below) and ring k + 1 (B, above).
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const int ca = p.counts[k], cb = p.counts[k + 1];
    const Index a0 = first[k], b0 = first[k + 1];
    int i = 0, j = 0;
    while (i < ca || j < cb) {
      const double next_a = p.offset[k] + static_cast<double>(i + 1) / ca;
      const double next_b = p.offset[k + 1] + static_cast<double>(j + 1) / cb;
      if (j == cb || (i < ca && next_a < next_b)) {
        m.F.push_back({a0 + i % ca, a0 + (i + 1) % ca, b0 + j % cb});
        ++i;
      } else {
        m.F.push_back({a0 + i % ca, b0 + (j + 1) % cb, b0 + j % cb});
        ++j;
      }
    }
  }
  // Top fan: (R_j, R_{j+1}, pole) faces up.
  {
    const int c = p.counts[n - 1];
    for (int j = 0; j < c; ++j) m.F.push_back({first[n - 1] + j, first[n - 1] + (j + 1) % c, first[n]});
  }
  return m;
}

// ---- the dumbbell's profile: ball arc, concave fillet, neck line, mirrored ----

struct Arc {
  double cx, cy, r, from, to;  // angles in radians; length r |to - from|
  double length() const { return r * std::abs(to - from); }
  Eigen::Vector2d at(double t) const {  // t in [0, 1]
    const double a = from + (to - from) * t;
    return {cx + r * std::cos(a), cy + r * std::sin(a)};
  }
};

struct DumbbellProfile {
  Arc ball;            // left ball, from the left pole over the top to the fillet tangent point
  Arc fillet;          // left fillet, from the tangent point down to the neck
  double neck_x0 = 0;  // straight neck from (neck_x0, neck_radius) to (-neck_x0, neck_radius)
  double neck_radius = 0;
  double half_length() const { return ball.length() + fillet.length() + (-neck_x0); }
  // Point at arc length s in [0, 2 half_length] from the left pole; the right half mirrors.
  Eigen::Vector2d at(double s) const {
    const double h = half_length();
    if (s > h) {
      Eigen::Vector2d q = at(2.0 * h - s);
      return {-q.x(), q.y()};
    }
    if (s <= ball.length()) return ball.at(s / ball.length());
    s -= ball.length();
    if (s <= fillet.length()) return fillet.at(s / fillet.length());
    s -= fillet.length();
    return {neck_x0 + s, neck_radius};
  }
};

}  // namespace

// === Tab. 2.3 polyhedra ===

PolygonMesh cube_quads(double edge) {
  detail::require_positive_length("cube_quads", "edge", edge);
  return cube_polygons(edge);
}

IndexedMesh cube_triangles(double edge) {
  detail::require_positive_length("cube_triangles", "edge", edge);
  return subdivided_cube(1, edge);
}

PolygonMesh double_cube_quads(double edge) {
  detail::require_positive_length("double_cube_quads", "edge", edge);
  const PolygonMesh one = cube_polygons(edge);
  return merged(one, translated(one, Eigen::Vector3d(2.0 * edge, 0.0, 0.0)));
}

PolygonMesh cube_with_face_hole(double edge) {
  detail::require_positive_length("cube_with_face_hole", "edge", edge);
  PolygonMesh m = cube_polygons(edge);
  const double q = 0.25 * edge, top = 0.5 * edge, floor = 0.0;
  // Rim of the pocket on the top face (8..11) and its floor (12..15), both CCW from above.
  const std::array<Eigen::Vector2d, 4> square = {Eigen::Vector2d(-q, -q), Eigen::Vector2d(q, -q), Eigen::Vector2d(q, q),
                                                 Eigen::Vector2d(-q, q)};
  std::array<Index, 4> rim{}, bottom{};
  for (std::size_t i = 0; i < 4; ++i) rim[i] = add_vertex(m.V, {square[i].x(), square[i].y(), top});
  for (std::size_t i = 0; i < 4; ++i) bottom[i] = add_vertex(m.V, {square[i].x(), square[i].y(), floor});
  // The hole loop runs CW seen from outside (+z).
  m.faces[kTopFace].holes.push_back({rim[0], rim[3], rim[2], rim[1]});
  // Pocket walls face into the pocket; the floor faces up.
  for (std::size_t i = 0; i < 4; ++i) {
    const std::size_t n = (i + 1) % 4;
    m.faces.push_back(PolygonFace{{rim[i], rim[n], bottom[n], bottom[i]}, {}});
  }
  m.faces.push_back(PolygonFace{{bottom[0], bottom[1], bottom[2], bottom[3]}, {}});
  return m;
}

namespace {

// Cube with a square tunnel along y. Front (-y) rim 8..11 and back (+y) rim 12..15, both
// listed in the (x, z) order (-,-) (+,-) (+,+) (-,+) of the front face's outer loop.
struct TunnelCube {
  PolygonMesh mesh;
  std::array<Index, 4> front{}, back{};
};

TunnelCube tunnel_cube(double edge) {
  TunnelCube t;
  t.mesh = cube_polygons(edge);
  const double q = 0.25 * edge, y = 0.5 * edge;
  const std::array<Eigen::Vector2d, 4> square = {Eigen::Vector2d(-q, -q), Eigen::Vector2d(q, -q), Eigen::Vector2d(q, q),
                                                 Eigen::Vector2d(-q, q)};
  for (std::size_t i = 0; i < 4; ++i) t.front[i] = add_vertex(t.mesh.V, {square[i].x(), -y, square[i].y()});
  for (std::size_t i = 0; i < 4; ++i) t.back[i] = add_vertex(t.mesh.V, {square[i].x(), y, square[i].y()});
  // Tunnel walls face the tunnel axis. The front rim in CW-from-front order is
  // f0 f3 f2 f1; each wall uses one of its edges reversed and the matching back edge.
  const std::array<Index, 4> cw = {t.front[0], t.front[3], t.front[2], t.front[1]};
  for (std::size_t i = 0; i < 4; ++i) {
    const Index a = cw[i], b = cw[(i + 1) % 4];
    t.mesh.faces.push_back(PolygonFace{{b, a, a + 4, b + 4}, {}});
  }
  // Back face: the rim in this order is CW seen from +y.
  t.mesh.faces[kBackFace].holes.push_back({t.back[0], t.back[1], t.back[2], t.back[3]});
  return t;
}

}  // namespace

PolygonMesh cube_with_tunnel(double edge) {
  detail::require_positive_length("cube_with_tunnel", "edge", edge);
  TunnelCube t = tunnel_cube(edge);
  t.mesh.faces[kFrontFace].holes.push_back({t.front[0], t.front[3], t.front[2], t.front[1]});
  return std::move(t.mesh);
}

PolygonMesh cube_with_tunnel_front_triangulated(double edge) {
  detail::require_positive_length("cube_with_tunnel_front_triangulated", "edge", edge);
  TunnelCube t = tunnel_cube(edge);
  // Replace the front face by the 8 triangles of the annulus between its outer loop O and
  // the rim I (same CCW order, I[i] is the rim corner nearest O[i]).
  const std::array<Index, 4> O = kCubeFaces[kFrontFace];
  const std::array<Index, 4>& I = t.front;
  std::vector<PolygonFace> faces;
  for (std::size_t f = 0; f < t.mesh.faces.size(); ++f)
    if (f != kFrontFace) faces.push_back(std::move(t.mesh.faces[f]));
  for (std::size_t i = 0; i < 4; ++i) {
    const std::size_t n = (i + 1) % 4;
    faces.push_back(PolygonFace{{O[i], O[n], I[n]}, {}});
    faces.push_back(PolygonFace{{O[i], I[n], I[i]}, {}});
  }
  t.mesh.faces = std::move(faces);
  return std::move(t.mesh);
}

// === Triangle meshes ===

IndexedMesh subdivided_cube(int n, double edge) {
  detail::require_at_least("subdivided_cube", "n", n, 1);
  detail::require_positive_length("subdivided_cube", "edge", edge);
  detail::require_triangle_budget("subdivided_cube", 12 * static_cast<std::int64_t>(n) * n);
  IndexedMesh m;
  // Surface points of the lattice {0..n}³, keyed by their lattice coordinates.
  std::unordered_map<std::int64_t, Index> index;
  const std::int64_t side = n + 1;
  auto vertex = [&](std::array<int, 3> c) {
    const std::int64_t key = (static_cast<std::int64_t>(c[0]) * side + c[1]) * side + c[2];
    auto [it, inserted] = index.try_emplace(key, static_cast<Index>(m.V.size()));
    if (inserted) {
      Vec3<double> p;
      for (int d = 0; d < 3; ++d) p[d] = (static_cast<double>(c[static_cast<std::size_t>(d)]) / n - 0.5) * edge;
      m.V.push_back(p);
    }
    return it->second;
  };
  m.F.reserve(12 * static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
  for (int d = 0; d < 3; ++d) {
    // Tangent axes with e_u x e_v = e_d.
    const auto u = static_cast<std::size_t>((d + 1) % 3), v = static_cast<std::size_t>((d + 2) % 3);
    for (int s : {0, n}) {
      const bool outward_is_plus = s == n;
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
          auto corner = [&](int da, int db) {
            std::array<int, 3> c{};
            c[static_cast<std::size_t>(d)] = s;
            c[u] = a + da;
            c[v] = b + db;
            return vertex(c);
          };
          // (a,b) (a+1,b) (a+1,b+1) (a,b+1) is CCW around +e_d.
          const Index p00 = corner(0, 0), p10 = corner(1, 0), p11 = corner(1, 1), p01 = corner(0, 1);
          if (outward_is_plus) {
            m.F.push_back({p00, p10, p11});
            m.F.push_back({p00, p11, p01});
          } else {
            m.F.push_back({p00, p11, p10});
            m.F.push_back({p00, p01, p11});
          }
        }
    }
  }
  return m;
}

IndexedMesh uv_sphere(int segments, int rings, double radius) {
  detail::require_at_least("uv_sphere", "segments", segments, 3);
  detail::require_at_least("uv_sphere", "rings", rings, 2);
  detail::require_positive_length("uv_sphere", "radius", radius);
  detail::require_triangle_budget("uv_sphere", 2 * static_cast<std::int64_t>(segments) * (rings - 1));
  RevolutionProfile p;
  for (int k = 0; k <= rings; ++k) {
    const double theta = kPi * k / rings;  // polar angle from the bottom pole
    p.z.push_back(k == 0 ? -radius : k == rings ? radius : -radius * std::cos(theta));
    p.rho.push_back(radius * std::sin(theta));
    p.counts.push_back(segments);
    p.offset.push_back(0.0);
  }
  return revolved_surface(p);
}

IndexedMesh geodesic_sphere(int frequency, double radius) {
  detail::require_at_least("geodesic_sphere", "frequency", frequency, 1);
  if (frequency > 2000)
    throw InputError(fmt::format("geodesic_sphere: frequency must be at most 2000, got {}", frequency));
  detail::require_positive_length("geodesic_sphere", "radius", radius);
  const IndexedMesh ico = icosphere(0, 1.0);  // outward-oriented icosahedron
  const auto f = static_cast<std::int64_t>(frequency);
  IndexedMesh out;
  // A grid point is the barycentric combination (a, b, c)/f of a face's corners. Points on a
  // shared edge or corner get the same key from both faces: the nonzero (corner, weight)
  // pairs, sorted by corner index.
  std::map<std::vector<std::int64_t>, Index> index_of;
  auto vertex = [&](const Triangle& face, std::int64_t a, std::int64_t b, std::int64_t c) {
    std::vector<std::pair<std::int64_t, std::int64_t>> parts;
    const std::int64_t w[3] = {a, b, c};
    for (int k = 0; k < 3; ++k)
      if (w[k] > 0) parts.push_back({face[static_cast<std::size_t>(k)], w[k]});
    std::sort(parts.begin(), parts.end());
    std::vector<std::int64_t> key;
    for (const auto& [corner, weight] : parts) {
      key.push_back(corner);
      key.push_back(weight);
    }
    auto [it, inserted] = index_of.try_emplace(key, static_cast<Index>(out.V.size()));
    if (inserted) {
      Vec3<double> p = Vec3<double>::Zero();
      for (const auto& [corner, weight] : parts)
        p += static_cast<double>(weight) * ico.V[static_cast<std::size_t>(corner)];
      out.V.push_back(radius * p.normalized());
    }
    return it->second;
  };
  for (const auto& face : ico.F) {
    // Rows i = 0..f from corner 0; point (i, j) = ((f-i), (i-j), j) / f.
    for (std::int64_t i = 0; i < f; ++i) {
      for (std::int64_t j = 0; j <= i; ++j) {
        const Index p00 = vertex(face, f - i, i - j, j);
        const Index p10 = vertex(face, f - i - 1, i + 1 - j, j);
        const Index p11 = vertex(face, f - i - 1, i - j, j + 1);
        out.F.push_back({p00, p10, p11});
        if (j < i) {
          const Index p01 = vertex(face, f - i, i - j - 1, j + 1);
          out.F.push_back({p00, p11, p01});
        }
      }
    }
  }
  return out;
}

IndexedMesh icosphere(int subdivisions, double radius) {
  detail::require_at_least("icosphere", "subdivisions", subdivisions, 0);
  if (subdivisions > 9)
    throw InputError(
        fmt::format("icosphere: subdivisions must be at most 9 (20·4^9 = 5.2 M triangles), got {}", subdivisions));
  detail::require_positive_length("icosphere", "radius", radius);
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  // clang-format off
  std::vector<Vec3<double>> V = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Triangle> F = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                             {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                             {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                             {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  // clang-format on
  for (auto& p : V) p.normalize();
  // The icosahedron is convex and centred: a face is outward iff its normal points away
  // from the origin. Fix any face listed the other way round.
  for (auto& f : F) {
    const auto& a = V[static_cast<std::size_t>(f[0])];
    const Vec3<double> nrm = (V[static_cast<std::size_t>(f[1])] - a).cross(V[static_cast<std::size_t>(f[2])] - a);
    if (nrm.dot(a) < 0.0) std::swap(f[1], f[2]);
  }
  for (int s = 0; s < subdivisions; ++s) {
    std::unordered_map<std::uint64_t, Index> midpoint;
    auto mid = [&](Index a, Index b) {
      const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
      auto [it, inserted] = midpoint.try_emplace((lo << 32) | hi, static_cast<Index>(V.size()));
      if (inserted) V.push_back((V[static_cast<std::size_t>(a)] + V[static_cast<std::size_t>(b)]).normalized());
      return it->second;
    };
    std::vector<Triangle> G;
    G.reserve(4 * F.size());
    for (const auto& f : F) {
      const Index ab = mid(f[0], f[1]), bc = mid(f[1], f[2]), ca = mid(f[2], f[0]);
      G.push_back({f[0], ab, ca});
      G.push_back({f[1], bc, ab});
      G.push_back({f[2], ca, bc});
      G.push_back({ab, bc, ca});
    }
    F = std::move(G);
  }
  for (auto& p : V) p *= radius;
  return IndexedMesh{std::move(V), std::move(F)};
}

IndexedMesh sphere_with_triangles(int triangles, double radius) {
  detail::require_at_least("sphere_with_triangles", "triangles", triangles, 6);
  if (triangles % 2 != 0)
    throw InputError(fmt::format(
        "sphere_with_triangles: triangles must be even (a closed triangle mesh has 3F = 2E), got {}", triangles));
  detail::require_positive_length("sphere_with_triangles", "radius", radius);
  // segments · bands = triangles / 2 with segments >= 3, bands >= 1; the best shape has
  // segments = 2 bands (the equator is twice as long as a meridian).
  const int half = triangles / 2;
  int best_segments = half, best_bands = 1;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int bands = 1; bands <= half / 3; ++bands) {
    if (half % bands != 0) continue;
    const int segments = half / bands;
    const double cost = std::abs(std::log(static_cast<double>(segments) / (2.0 * bands)));
    if (cost < best_cost) {
      best_cost = cost;
      best_segments = segments;
      best_bands = bands;
    }
  }
  return uv_sphere(best_segments, best_bands + 1, radius);
}

IndexedMesh cylinder(double radius, double height, int segments) {
  detail::require_positive_length("cylinder", "radius", radius);
  detail::require_positive_length("cylinder", "height", height);
  detail::require_at_least("cylinder", "segments", segments, 3);
  detail::require_triangle_budget("cylinder", 4 * static_cast<std::int64_t>(segments));
  IndexedMesh m;
  const int n = segments;
  for (const double z : {-0.5 * height, 0.5 * height})
    for (int i = 0; i < n; ++i) {
      const double a = 2.0 * kPi * i / n;
      m.V.emplace_back(radius * std::cos(a), radius * std::sin(a), z);
    }
  const auto bottom = static_cast<Index>(2 * n), top = static_cast<Index>(2 * n + 1);
  m.V.emplace_back(0.0, 0.0, -0.5 * height);
  m.V.emplace_back(0.0, 0.0, 0.5 * height);
  auto b = [&](int i) { return static_cast<Index>(i % n); };
  auto t = [&](int i) { return static_cast<Index>(n + i % n); };
  for (int i = 0; i < n; ++i) {
    m.F.push_back({top, t(i), t(i + 1)});       // CCW seen from +z
    m.F.push_back({bottom, b(i + 1), b(i)});    // CCW seen from -z
    m.F.push_back({b(i), b(i + 1), t(i + 1)});  // (tangent) x (tangent + z) points out
    m.F.push_back({b(i), t(i + 1), t(i)});
  }
  return m;
}

IndexedMesh torus(double major_radius, double minor_radius, int major_segments, int minor_segments) {
  detail::require_positive_length("torus", "major_radius", major_radius);
  detail::require_positive_length("torus", "minor_radius", minor_radius);
  if (!(minor_radius < major_radius))
    throw InputError(fmt::format("torus: minor_radius ({}) must be smaller than major_radius ({}) for a ring torus",
                                 minor_radius, major_radius));
  detail::require_at_least("torus", "major_segments", major_segments, 3);
  detail::require_at_least("torus", "minor_segments", minor_segments, 3);
  detail::require_triangle_budget("torus", 2 * static_cast<std::int64_t>(major_segments) * minor_segments);
  IndexedMesh m;
  const int nu = major_segments, nv = minor_segments;
  for (int i = 0; i < nu; ++i) {
    const double u = 2.0 * kPi * i / nu;
    for (int j = 0; j < nv; ++j) {
      const double v = 2.0 * kPi * j / nv;
      const double w = major_radius + minor_radius * std::cos(v);
      m.V.emplace_back(w * std::cos(u), w * std::sin(u), minor_radius * std::sin(v));
    }
  }
  // d/du x d/dv points out of the tube, so (i,j) (i+1,j) (i+1,j+1) (i,j+1) is CCW outside.
  auto id = [&](int i, int j) { return static_cast<Index>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.F.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.F.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

IndexedMesh dumbbell(const DumbbellOptions& o) {
  detail::require_positive_length("dumbbell", "ball_radius_m", o.ball_radius_m);
  detail::require_positive_length("dumbbell", "ball_gap_m", o.ball_gap_m);
  detail::require_positive_length("dumbbell", "neck_radius_m", o.neck_radius_m);
  detail::require_positive_length("dumbbell", "fillet_radius_m", o.fillet_radius_m);
  detail::require_positive_length("dumbbell", "edge_length_m", o.edge_length_m);
  if (!(o.neck_radius_m < o.ball_radius_m))
    throw InputError(fmt::format("dumbbell: neck_radius_m ({}) must be smaller than ball_radius_m ({})",
                                 o.neck_radius_m, o.ball_radius_m));
  if (!(o.edge_length_m < o.ball_radius_m))
    throw InputError(fmt::format("dumbbell: edge_length_m ({}) must be smaller than ball_radius_m ({})",
                                 o.edge_length_m, o.ball_radius_m));
  const double R = o.ball_radius_m, rn = o.neck_radius_m, rf = o.fillet_radius_m;
  const double a = R + 0.5 * o.ball_gap_m;  // ball centres at x = -a and x = +a
  // Left fillet centre (xc, rn + rf): tangent to the neck line y = rn and externally
  // tangent to the left ball.
  const double xc = -a + std::sqrt((R + rf) * (R + rf) - (rn + rf) * (rn + rf));
  if (!(xc < 0.0))
    throw InputError(
        fmt::format("dumbbell: the fillets (radius {}) do not fit in a ball gap of {}; increase ball_gap_m or reduce "
                    "fillet_radius_m",
                    rf, o.ball_gap_m));
  DumbbellProfile prof;
  const double tangent_angle = std::atan2(rn + rf, xc + a);  // on the ball, seen from its centre
  prof.ball = Arc{-a, 0.0, R, kPi, tangent_angle};
  prof.fillet = Arc{xc, rn + rf, rf, std::atan2(-(rn + rf), -a - xc), -0.5 * kPi};
  prof.neck_x0 = xc;
  prof.neck_radius = rn;

  const double length = 2.0 * prof.half_length();
  const int n = std::max(4, static_cast<int>(std::lround(length / o.edge_length_m)));
  detail::require_triangle_budget(
      "dumbbell", static_cast<std::int64_t>(n) * static_cast<std::int64_t>(4.0 * kPi * R / o.edge_length_m));
  RevolutionProfile p;
  for (int k = 0; k <= n; ++k) {
    const Eigen::Vector2d q = prof.at(length * k / n);
    p.z.push_back(k == 0 ? -a - R : k == n ? a + R : q.x());
    p.rho.push_back(q.y());
    const int c = std::max(3, static_cast<int>(std::lround(2.0 * kPi * q.y() / o.edge_length_m)));
    p.counts.push_back(c);
    p.offset.push_back((k % 2 == 1) ? 0.5 / c : 0.0);  // stagger rings for better triangles
  }
  IndexedMesh m = revolved_surface(p);
  // Axis z -> x by the cyclic permutation (x, y, z) -> (z, x, y), a proper rotation.
  for (auto& v : m.V) v = Vec3<double>(v.z(), v.x(), v.y());
  return m;
}

IndexedMesh benchmark_object(char which) {
  switch (std::toupper(static_cast<unsigned char>(which))) {
    case 'A':
      return subdivided_cube(4, 0.1);
    case 'B':
      return uv_sphere(100, 81, 0.05);
    case 'C':
      return uv_sphere(160, 101, 0.05);
    default:
      throw InputError(fmt::format("benchmark_object: unknown object '{}' (use A, B or C of Tab. 5.1)", which));
  }
}

}  // namespace meltlab::datasets
