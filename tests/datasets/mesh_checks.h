#pragma once
// Independent geometric checks for the dataset tests: written here from first principles,
// not shared with the library, so a bug in the generators cannot hide behind the same bug
// in the check.

#include <meltlab/core/error.h>
#include <meltlab/sim/mesh.h>
#include <meltlab/sim/polygon_mesh.h>
#include <meltlab/sim/topology.h>

#include "test_files.h"

#include <fmt/format.h>
#include <unistd.h>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::test {

/// Signed volume by the divergence theorem: sum of a · (b × c) / 6; positive for a closed
/// mesh oriented outward.
inline double signed_volume(const sim::IndexedMesh& m) {
  double v = 0.0;
  for (const auto& t : m.F) {
    const auto& a = m.V[static_cast<std::size_t>(t[0])];
    const auto& b = m.V[static_cast<std::size_t>(t[1])];
    const auto& c = m.V[static_cast<std::size_t>(t[2])];
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

inline sim::TopologyReport topology_of(const sim::IndexedMesh& m) {
  return sim::check_topology(sim::TriMesh<double>::from_indexed(m));
}

/// Lengths of all undirected edges (each once).
inline std::vector<double> edge_lengths(const sim::IndexedMesh& m) {
  std::vector<double> out;
  for (const auto& t : m.F)
    for (int i = 0; i < 3; ++i) {
      const auto a = t[static_cast<std::size_t>(i)], b = t[static_cast<std::size_t>((i + 1) % 3)];
      if (a < b) out.push_back((m.V[static_cast<std::size_t>(a)] - m.V[static_cast<std::size_t>(b)]).norm());
    }
  return out;
}

/// Smallest interior angle of triangle (a, b, c), degrees.
inline double min_angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  auto angle = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& r) {
    const Eigen::Vector3d u = q - p, v = r - p;
    return std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / std::numbers::pi;
  };
  return std::min({angle(a, b, c), angle(b, c, a), angle(c, a, b)});
}

/// Shells S of a polygon mesh counting a face's hole loops as part of the face (vertices
/// of a face's outer and hole loops are one piece of surface).
inline std::int64_t shells_through_faces(const sim::PolygonMesh& m) {
  std::vector<std::size_t> parent(m.V.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<char> used(m.V.size(), 0);
  for (const auto& f : m.faces) {
    const auto root = static_cast<std::size_t>(f.outer.front());
    auto join = [&](sim::Index v) {
      used[static_cast<std::size_t>(v)] = 1;
      parent[find(static_cast<std::size_t>(v))] = find(root);
    };
    for (auto v : f.outer) join(v);
    for (const auto& h : f.holes)
      for (auto v : h) join(v);
  }
  std::int64_t s = 0;
  for (std::size_t v = 0; v < m.V.size(); ++v) s += (used[v] && find(v) == v) ? 1 : 0;
  return s;
}

/// Number of undirected edges of a polygon mesh (outer and hole loops).
inline std::int64_t edge_count(const sim::PolygonMesh& m) {
  std::vector<std::pair<sim::Index, sim::Index>> e;
  auto add = [&](const std::vector<sim::Index>& loop) {
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const auto a = loop[k], b = loop[(k + 1) % loop.size()];
      e.emplace_back(std::min(a, b), std::max(a, b));
    }
  };
  for (const auto& f : m.faces) {
    add(f.outer);
    for (const auto& h : f.holes) add(h);
  }
  std::sort(e.begin(), e.end());
  return std::unique(e.begin(), e.end()) - e.begin();
}

// ---- 2-D polygons ----

inline double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

/// Index pairs of non-adjacent edges that intersect or touch (brute force, O(n²)).
inline std::optional<std::pair<std::size_t, std::size_t>> first_self_intersection(
    const std::vector<Eigen::Vector2d>& p) {
  const std::size_t n = p.size();
  auto between = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& q) {
    return std::min(a.x(), b.x()) <= q.x() && q.x() <= std::max(a.x(), b.x()) && std::min(a.y(), b.y()) <= q.y() &&
           q.y() <= std::max(a.y(), b.y());
  };
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j + 1 == n) continue;
      const auto &a = p[i], &b = p[(i + 1) % n], &c = p[j], &d = p[(j + 1) % n];
      const double d1 = cross2(a, b, c), d2 = cross2(a, b, d), d3 = cross2(c, d, a), d4 = cross2(c, d, b);
      const bool proper = ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0)) && d1 != 0 && d2 != 0 && d3 != 0 && d4 != 0;
      const bool touch = (d1 == 0 && between(a, b, c)) || (d2 == 0 && between(a, b, d)) ||
                         (d3 == 0 && between(c, d, a)) || (d4 == 0 && between(c, d, b));
      if (proper || touch) return std::make_pair(i, j);
    }
  return std::nullopt;
}

inline double distance_to_segment(const Eigen::Vector2d& q, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - q).norm();
}

/// Even-odd point-in-polygon test.
inline bool inside_polygon(const std::vector<Eigen::Vector2d>& p, const Eigen::Vector2d& q) {
  bool in = false;
  for (std::size_t i = 0, j = p.size() - 1; i < p.size(); j = i++)
    if ((p[i].y() > q.y()) != (p[j].y() > q.y()) &&
        q.x() < (p[j].x() - p[i].x()) * (q.y() - p[i].y()) / (p[j].y() - p[i].y()) + p[i].x())
      in = !in;
  return in;
}

}  // namespace meltlab::test
