#include <meltlab/core/error.h>
#include <meltlab/sim/polygon_mesh.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

namespace meltlab::sim {

std::size_t PolygonMesh::hole_count() const {
  std::size_t h = 0;
  for (const auto& f : faces) h += f.holes.size();
  return h;
}

namespace {

// Representative (smallest original index) of every vertex after merging coincident ones.
std::vector<Index> coincident_representatives(const std::vector<Vec3<double>>& V, double tolerance) {
  const std::size_t n = V.size();
  std::vector<Index> rep(n);
  std::iota(rep.begin(), rep.end(), 0);
  if (tolerance <= 0.0) {
    std::vector<Index> order(n);
    std::iota(order.begin(), order.end(), 0);
    auto key_less = [&](Index a, Index b) {
      const auto& p = V[static_cast<std::size_t>(a)];
      const auto& q = V[static_cast<std::size_t>(b)];
      if (p.x() != q.x()) return p.x() < q.x();
      if (p.y() != q.y()) return p.y() < q.y();
      if (p.z() != q.z()) return p.z() < q.z();
      return a < b;
    };
    std::sort(order.begin(), order.end(), key_less);
    for (std::size_t k = 1; k < n; ++k) {
      const auto prev = static_cast<std::size_t>(order[k - 1]);
      const auto cur = static_cast<std::size_t>(order[k]);
      if (V[prev] == V[cur]) rep[cur] = rep[prev];  // run start has the smallest index
    }
    return rep;
  }
  // Tolerance: uniform hash grid with cell = tolerance; union-find over close pairs.
  auto find = [&](Index x) {
    while (rep[static_cast<std::size_t>(x)] != x) {
      auto& r = rep[static_cast<std::size_t>(x)];
      r = rep[static_cast<std::size_t>(r)];
      x = r;
    }
    return x;
  };
  struct CellHash {
    std::size_t operator()(const std::array<std::int64_t, 3>& c) const {
      return static_cast<std::size_t>(c[0] * 73856093LL ^ c[1] * 19349663LL ^ c[2] * 83492791LL);
    }
  };
  std::unordered_map<std::array<std::int64_t, 3>, std::vector<Index>, CellHash> grid;
  grid.reserve(n);
  const double tol2 = tolerance * tolerance;
  for (std::size_t k = 0; k < n; ++k) {
    std::array<std::int64_t, 3> c{};
    for (int d = 0; d < 3; ++d)
      c[static_cast<std::size_t>(d)] = static_cast<std::int64_t>(std::floor(V[k][d] / tolerance));
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (Index j : it->second) {
            if ((V[static_cast<std::size_t>(j)] - V[k]).squaredNorm() <= tol2) {
              Index a = find(j), b = find(static_cast<Index>(k));
              if (a != b) rep[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
            }
          }
        }
    grid[c].push_back(static_cast<Index>(k));
  }
  for (std::size_t k = 0; k < n; ++k) rep[k] = find(static_cast<Index>(k));
  return rep;
}

// Removes consecutive duplicates in a closed loop (after welding) and returns it.
std::vector<Index> clean_loop(const std::vector<Index>& loop, const std::vector<Index>& map) {
  std::vector<Index> out;
  out.reserve(loop.size());
  for (Index v : loop) {
    const Index w = map[static_cast<std::size_t>(v)];
    if (out.empty() || out.back() != w) out.push_back(w);
  }
  while (out.size() > 1 && out.front() == out.back()) out.pop_back();
  return out;
}

}  // namespace

WeldResult weld_vertices(const PolygonMesh& in, double tolerance) {
  WeldResult result;
  const auto rep = coincident_representatives(in.V, tolerance);
  // Which representatives are referenced by a surviving face.
  std::vector<PolygonFace> faces;
  faces.reserve(in.faces.size());
  for (const auto& f : in.faces) {
    PolygonFace g;
    g.outer = clean_loop(f.outer, rep);
    std::vector<Index> sorted = g.outer;
    std::sort(sorted.begin(), sorted.end());
    const bool distinct = std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
    if (g.outer.size() < 3 || !distinct) {
      ++result.degenerate_faces_removed;
      continue;
    }
    for (const auto& h : f.holes) {
      auto hh = clean_loop(h, rep);
      if (hh.size() >= 3) g.holes.push_back(std::move(hh));
    }
    faces.push_back(std::move(g));
  }
  std::vector<std::uint8_t> used(in.V.size(), 0);
  for (const auto& f : faces) {
    for (Index v : f.outer) used[static_cast<std::size_t>(v)] = 1;
    for (const auto& h : f.holes)
      for (Index v : h) used[static_cast<std::size_t>(v)] = 1;
  }
  std::vector<Index> compact(in.V.size(), -1);
  for (std::size_t k = 0; k < in.V.size(); ++k) {
    if (rep[k] != static_cast<Index>(k)) {
      ++result.merged_vertices;
      continue;
    }
    if (!used[k]) {
      ++result.unreferenced_removed;
      continue;
    }
    compact[k] = static_cast<Index>(result.mesh.V.size());
    result.mesh.V.push_back(in.V[k]);
  }
  for (auto& f : faces) {
    for (Index& v : f.outer) v = compact[static_cast<std::size_t>(v)];
    for (auto& h : f.holes)
      for (Index& v : h) v = compact[static_cast<std::size_t>(v)];
  }
  result.mesh.faces = std::move(faces);
  return result;
}

namespace {

// Ear clipping of one simple polygon (projected on the plane of its Newell normal).
void triangulate_loop(const std::vector<Vec3<double>>& V, const std::vector<Index>& loop, std::vector<Triangle>& out) {
  const std::size_t n = loop.size();
  if (n == 3) {
    out.push_back({loop[0], loop[1], loop[2]});
    return;
  }
  Vec3<double> normal = Vec3<double>::Zero();  // Newell's method
  for (std::size_t k = 0; k < n; ++k) {
    const auto& p = V[static_cast<std::size_t>(loop[k])];
    const auto& q = V[static_cast<std::size_t>(loop[(k + 1) % n])];
    normal += Vec3<double>((p.y() - q.y()) * (p.z() + q.z()), (p.z() - q.z()) * (p.x() + q.x()),
                           (p.x() - q.x()) * (p.y() + q.y()));
  }
  int drop = 0;  // drop the dominant axis
  if (std::abs(normal.y()) > std::abs(normal[drop])) drop = 1;
  if (std::abs(normal.z()) > std::abs(normal[drop])) drop = 2;
  const int u = (drop + 1) % 3, w = (drop + 2) % 3;
  const double sign = normal[drop] >= 0 ? 1.0 : -1.0;
  auto p2 = [&](Index v) {
    const auto& p = V[static_cast<std::size_t>(v)];
    return std::array<double, 2>{p[u], p[w]};
  };
  auto cross2 = [&](Index a, Index b, Index c) {
    const auto A = p2(a), B = p2(b), C = p2(c);
    return sign * ((B[0] - A[0]) * (C[1] - A[1]) - (B[1] - A[1]) * (C[0] - A[0]));
  };
  std::vector<Index> poly = loop;
  std::size_t guard = 0;
  while (poly.size() > 3 && guard < 4 * n * n) {
    ++guard;
    bool clipped = false;
    for (std::size_t k = 0; k < poly.size(); ++k) {
      const std::size_t m = poly.size();
      const Index a = poly[(k + m - 1) % m], b = poly[k], c = poly[(k + 1) % m];
      if (cross2(a, b, c) <= 0) continue;  // reflex or flat corner
      bool contains = false;
      for (Index x : poly) {
        if (x == a || x == b || x == c) continue;
        if (cross2(a, b, x) >= 0 && cross2(b, c, x) >= 0 && cross2(c, a, x) >= 0) {
          contains = true;
          break;
        }
      }
      if (contains) continue;
      out.push_back({a, b, c});
      poly.erase(poly.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
      break;
    }
    if (!clipped) break;  // degenerate polygon: fall back to a fan below
  }
  for (std::size_t k = 1; k + 1 < poly.size(); ++k) out.push_back({poly[0], poly[k], poly[k + 1]});
}

}  // namespace

IndexedMesh triangulate(const PolygonMesh& in, const std::string& source) {
  IndexedMesh out;
  out.V = in.V;
  out.F.reserve(in.faces.size());
  for (std::size_t f = 0; f < in.faces.size(); ++f) {
    if (!in.faces[f].holes.empty())
      throw InputError(fmt::format("{}: face {} has holes; only simple polygons can be triangulated", source, f));
    triangulate_loop(in.V, in.faces[f].outer, out.F);
  }
  return out;
}

PolygonMesh to_polygon_mesh(const IndexedMesh& m) {
  PolygonMesh out;
  out.V = m.V;
  out.faces.reserve(m.F.size());
  for (const auto& t : m.F) out.faces.push_back({{t[0], t[1], t[2]}, {}});
  return out;
}

}  // namespace meltlab::sim
