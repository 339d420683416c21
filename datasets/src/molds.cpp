// Mold blocks (molds.h): smoothed outline -> resampled outline -> CGAL quality mesh of the
// top/bottom faces -> extruded closed block, with the mesh size chosen so the triangle
// count is close to the target.

#include <meltlab/datasets/molds.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "checks.h"
#include "mold_outlines.h"
#include "planar_meshing.h"

namespace meltlab::datasets {

using detail::ControlPoint;
using sim::Index;
using sim::IndexedMesh;
using Point2 = Eigen::Vector2d;

namespace {

constexpr double kOutlineSpacingMm = 0.5;    // sampling of the smoothed outline
constexpr double kMinTargetTriangles = 200;  // below this a mold is no longer its shape
// Boundary vertex spacing as a fraction of CGAL's edge-length bound h. The refined
// interior has edges between about h/2 and h; this makes the outline edges (and the wall
// quads) about as long as the interior edges, so triangle size is uniform over the block.
constexpr double kBoundarySpacingPerBound = 0.7;
// Stop the size search when the count is this close to the target (relative).
constexpr double kCountGoodEnough = 0.002;
constexpr int kMaxSearchSteps = 40;

// ---- smoothing ----

// Point at parameter t in [t1, t2] of the centripetal Catmull-Rom segment P1 -> P2
// (Barry-Goldman pyramid).
Point2 catmull_rom(const Point2& p0, const Point2& p1, const Point2& p2, const Point2& p3, double u) {
  auto knot = [](double t, const Point2& a, const Point2& b) { return t + std::sqrt(std::max((b - a).norm(), 1e-12)); };
  const double t0 = 0.0, t1 = knot(t0, p0, p1), t2 = knot(t1, p1, p2), t3 = knot(t2, p2, p3);
  const double t = t1 + (t2 - t1) * u;
  auto lerp = [t](const Point2& a, const Point2& b, double ta, double tb) -> Point2 {
    return ((tb - t) * a + (t - ta) * b) / (tb - ta);
  };
  const Point2 a1 = lerp(p0, p1, t0, t1), a2 = lerp(p1, p2, t1, t2), a3 = lerp(p2, p3, t2, t3);
  const Point2 b1 = lerp(a1, a2, t0, t2), b2 = lerp(a2, a3, t1, t3);
  return lerp(b1, b2, t1, t2);
}

struct Outline {
  std::vector<Point2> p;     // closed polyline, first point not repeated
  std::vector<char> corner;  // 1 where the outline keeps a sharp corner
};

// The centripetal Catmull-Rom spline through the control points, sampled at <= 0.5 mm.
// At a corner point the neighbouring segments use a reflected phantom point instead of
// the point beyond the corner, so each ends with the direction of its own chord.
Outline smoothed_outline(Mold mold) {
  const std::vector<ControlPoint> c = detail::mold_control_points(mold);
  const std::size_t n = c.size();
  Outline out;
  auto pt = [&](std::size_t i) { return Point2(c[i % n].x_mm, c[i % n].y_mm); };
  for (std::size_t i = 0; i < n; ++i) {
    const Point2 p1 = pt(i), p2 = pt(i + 1);
    const Point2 p0 = c[i].corner ? Point2(2.0 * p1 - p2) : pt(i + n - 1);
    const Point2 p3 = c[(i + 1) % n].corner ? Point2(2.0 * p2 - p1) : pt(i + 2);
    // The spline's parameter is not arc length: refine until no step exceeds the spacing.
    int m = std::max(2, static_cast<int>(std::ceil((p2 - p1).norm() / kOutlineSpacingMm)));
    std::vector<Point2> seg;
    for (int attempt = 0; attempt < 16; ++attempt) {
      seg.clear();
      for (int k = 0; k < m; ++k) seg.push_back(k == 0 ? p1 : catmull_rom(p0, p1, p2, p3, static_cast<double>(k) / m));
      seg.push_back(p2);
      double longest = 0.0;
      for (std::size_t k = 0; k + 1 < seg.size(); ++k) longest = std::max(longest, (seg[k + 1] - seg[k]).norm());
      if (longest <= kOutlineSpacingMm) break;
      m = static_cast<int>(std::ceil(m * longest / kOutlineSpacingMm)) + 1;
    }
    seg.pop_back();  // p2 starts the next segment
    for (std::size_t k = 0; k < seg.size(); ++k) {
      out.p.push_back(seg[k]);
      out.corner.push_back(k == 0 && c[i].corner ? 1 : 0);
    }
  }
  // Centre the bounding box on the origin.
  Point2 lo = out.p.front(), hi = out.p.front();
  for (const auto& q : out.p) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const Point2 centre = 0.5 * (lo + hi);
  for (auto& q : out.p) q -= centre;
  return out;
}

// Resamples the outline at about `spacing` (mm) by arc length, keeping every corner.
std::vector<Point2> resampled(const Outline& o, double spacing) {
  const std::size_t n = o.p.size();
  std::vector<std::size_t> anchors;
  for (std::size_t i = 0; i < n; ++i)
    if (o.corner[i]) anchors.push_back(i);
  const bool closed_run = anchors.empty();
  if (closed_run) anchors.push_back(0);
  std::vector<Point2> out;
  for (std::size_t a = 0; a < anchors.size(); ++a) {
    const std::size_t from = anchors[a];
    const std::size_t to = anchors[(a + 1) % anchors.size()] + (a + 1 == anchors.size() ? n : 0);
    // Run from..to (indices mod n), to > from.
    std::vector<double> s{0.0};
    for (std::size_t i = from; i < to; ++i) s.push_back(s.back() + (o.p[(i + 1) % n] - o.p[i % n]).norm());
    const double length = s.back();
    const int pieces = std::max(closed_run ? 3 : 1, static_cast<int>(std::lround(length / spacing)));
    std::size_t seg = 0;
    for (int j = 0; j < pieces; ++j) {
      const double target = length * j / pieces;
      while (seg + 1 < s.size() - 1 && s[seg + 1] < target) ++seg;
      const double len = s[seg + 1] - s[seg];
      const double u = len > 0.0 ? (target - s[seg]) / len : 0.0;
      out.push_back((1.0 - u) * o.p[(from + seg) % n] + u * o.p[(from + seg + 1) % n]);
    }
  }
  return out;
}

double orient(const Point2& a, const Point2& b, const Point2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

bool on_segment(const Point2& a, const Point2& b, const Point2& p) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) && std::min(a.y(), b.y()) <= p.y() &&
         p.y() <= std::max(a.y(), b.y());
}

bool segments_touch(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return true;
  return (o1 == 0 && on_segment(a, b, c)) || (o2 == 0 && on_segment(a, b, d)) || (o3 == 0 && on_segment(c, d, a)) ||
         (o4 == 0 && on_segment(c, d, b));
}

// True if no two non-adjacent edges touch and no two adjacent edges fold back on each
// other. O(n²) with a bounding-box reject; n is a few hundred to a few thousand.
bool is_simple(const std::vector<Point2>& p) {
  const std::size_t n = p.size();
  if (n < 3) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const Point2 &a = p[i], &b = p[(i + 1) % n], &c = p[(i + 2) % n];
    if (a == b) return false;
    if (orient(a, b, c) == 0.0 && (b - a).dot(c - b) < 0.0) return false;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Point2 &a = p[i], &b = p[(i + 1) % n];
    const Point2 lo = a.cwiseMin(b), hi = a.cwiseMax(b);
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through the wrap
      const Point2 &c = p[j], &d = p[(j + 1) % n];
      if (std::max(c.x(), d.x()) < lo.x() || std::min(c.x(), d.x()) > hi.x() || std::max(c.y(), d.y()) < lo.y() ||
          std::min(c.y(), d.y()) > hi.y())
        continue;
      if (segments_touch(a, b, c, d)) return false;
    }
  }
  return true;
}

// ---- the block ----

// Extrudes a planar mesh (mm) from z = 0 to z = thickness (m) with `rows` rows of wall.
IndexedMesh extruded_block(const detail::PlanarMesh& pm, double thickness_m, int rows) {
  constexpr double kMetresPerMm = 1e-3;
  const auto n = static_cast<Index>(pm.V.size());
  const auto nb = static_cast<Index>(pm.boundary.size());
  IndexedMesh m;
  m.V.reserve(2 * pm.V.size() + static_cast<std::size_t>(rows - 1) * pm.boundary.size());
  for (int layer = 0; layer < 2; ++layer)
    for (const auto& q : pm.V) m.V.emplace_back(q.x() * kMetresPerMm, q.y() * kMetresPerMm, layer * thickness_m);
  for (int k = 1; k < rows; ++k)
    for (int b : pm.boundary) {
      const auto& q = pm.V[static_cast<std::size_t>(b)];
      m.V.emplace_back(q.x() * kMetresPerMm, q.y() * kMetresPerMm, thickness_m * k / rows);
    }
  m.F.reserve(2 * pm.F.size() + 2 * static_cast<std::size_t>(rows) * pm.boundary.size());
  for (const auto& t : pm.F) m.F.push_back({t[0], t[2], t[1]});              // bottom, faces -z
  for (const auto& t : pm.F) m.F.push_back({n + t[0], n + t[1], n + t[2]});  // top, faces +z
  auto wall_vertex = [&](int k, Index b) -> Index {
    b %= nb;
    if (k == 0) return pm.boundary[static_cast<std::size_t>(b)];
    if (k == rows) return n + pm.boundary[static_cast<std::size_t>(b)];
    return 2 * n + (k - 1) * nb + b;
  };
  // The boundary runs CCW seen from above, so (b, b+1, up) is CCW seen from outside.
  for (int k = 0; k < rows; ++k)
    for (Index b = 0; b < nb; ++b) {
      const Index q0 = wall_vertex(k, b), q1 = wall_vertex(k, b + 1), q2 = wall_vertex(k + 1, b + 1),
                  q3 = wall_vertex(k + 1, b);
      m.F.push_back({q0, q1, q2});
      m.F.push_back({q0, q2, q3});
    }
  return m;
}

struct Attempt {
  double size_bound_mm = 0;
  detail::PlanarMesh planar;
  std::int64_t triangles = 0;
};

}  // namespace

std::string mold_name(Mold mold) {
  switch (mold) {
    case Mold::kGiraffe:
      return "giraffe";
    case Mold::kAirplane:
      return "airplane";
    case Mold::kShip:
      return "ship";
    case Mold::kWarship:
      return "warship";
  }
  throw InputError(fmt::format("mold_name: invalid mold value {}", static_cast<int>(mold)));
}

Mold mold_from_name(std::string_view name) {
  for (Mold m : kAllMolds)
    if (mold_name(m) == name) return m;
  throw InputError(fmt::format("unknown mold '{}' (use giraffe, airplane, ship or warship)", name));
}

int mold_reference_triangles(Mold mold) {
  switch (mold) {
    case Mold::kGiraffe:
      return 10823;
    case Mold::kAirplane:
      return 10683;
    case Mold::kShip:
      return 10874;
    case Mold::kWarship:
      return 10799;
  }
  throw InputError(fmt::format("mold_reference_triangles: invalid mold value {}", static_cast<int>(mold)));
}

std::vector<Eigen::Vector2d> mold_outline_mm(Mold mold) { return smoothed_outline(mold).p; }

double polygon_area(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& a = polygon[i];
    const auto& b = polygon[(i + 1) % polygon.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * twice;
}

MoldBlock mold_block(Mold mold, const MoldOptions& options) {
  const std::string name = mold_name(mold);
  const std::string who = fmt::format("mold {}", name);
  const int target = options.target_triangles == 0 ? mold_reference_triangles(mold) : options.target_triangles;
  if (target < kMinTargetTriangles)
    throw InputError(fmt::format("{}: target_triangles must be 0 (the monograph's count) or at least {}, got {}", who,
                                 kMinTargetTriangles, options.target_triangles));
  if (!(options.max_count_error > 0.0) || !(options.max_count_error < 1.0))
    throw InputError(fmt::format("{}: max_count_error must be in (0, 1), got {}", who, options.max_count_error));
  const Outline outline = smoothed_outline(mold);
  const double area_mm2 = polygon_area(outline.p);
  double perimeter_mm = 0.0;
  for (std::size_t i = 0; i < outline.p.size(); ++i)
    perimeter_mm += (outline.p[(i + 1) % outline.p.size()] - outline.p[i]).norm();

  MoldBlock block;
  block.outline_area_m2 = area_mm2 * 1e-6;
  if (options.thickness_m > 0.0) {
    detail::require_positive_length(who, "thickness_m", options.thickness_m);
    block.thickness_m = options.thickness_m;
  } else {
    if (options.thickness_m < 0.0 || !std::isfinite(options.thickness_m))
      throw InputError(fmt::format("{}: thickness_m must be > 0, or 0 to derive it from the ice mass, got {}", who,
                                   options.thickness_m));
    if (!(options.ice_mass_kg > 0.0) || !std::isfinite(options.ice_mass_kg))
      throw InputError(fmt::format("{}: ice_mass_kg must be positive, got {}", who, options.ice_mass_kg));
    if (!(options.ice_density_kg_m3 > 0.0) || !std::isfinite(options.ice_density_kg_m3))
      throw InputError(fmt::format("{}: ice_density_kg_m3 must be positive, got {}", who, options.ice_density_kg_m3));
    block.thickness_m = options.ice_mass_kg / (options.ice_density_kg_m3 * block.outline_area_m2);
  }
  const double thickness_mm = block.thickness_m * 1e3;

  // First guess of h: the surface (2 faces + wall) split into `target` triangles of mean
  // area 0.25 h² (measured for CGAL's refinement with shape bound 0.125). The wall rows
  // are fixed from this guess so the count varies smoothly with h during the search.
  const double surface_mm2 = 2.0 * area_mm2 + perimeter_mm * thickness_mm;
  const double h0 = std::sqrt(surface_mm2 / (0.25 * target));
  const int rows = std::max(1, static_cast<int>(std::lround(thickness_mm / (kBoundarySpacingPerBound * h0))));

  auto attempt = [&](double h) {
    Attempt a;
    a.size_bound_mm = h;
    const std::vector<Point2> polygon = resampled(outline, kBoundarySpacingPerBound * h);
    if (!is_simple(polygon))
      throw InputError(fmt::format("{}: {} triangles is too coarse: the outline resampled at {:.2f} mm crosses itself",
                                   who, target, kBoundarySpacingPerBound * h));
    a.planar = detail::refined_polygon_mesh(polygon, h, who);
    a.triangles = 2 * static_cast<std::int64_t>(a.planar.F.size()) +
                  2 * static_cast<std::int64_t>(rows) * static_cast<std::int64_t>(a.planar.boundary.size());
    return a;
  };
  auto error = [&](const Attempt& a) { return std::abs(static_cast<double>(a.triangles - target)) / target; };

  // Search h: the count falls roughly as 1/h², so step by sqrt(count / target) and keep a
  // bracket [too fine, too coarse]; bisect (geometrically) when a step leaves it.
  std::optional<Attempt> best;
  double fine = 0.0, coarse = std::numeric_limits<double>::infinity();
  double h = h0;
  for (int step = 0; step < kMaxSearchSteps; ++step) {
    Attempt a = attempt(h);
    const bool too_many = a.triangles > target;
    const double ratio = static_cast<double>(a.triangles) / target;
    if (!best || error(a) < error(*best)) best = std::move(a);
    if (error(*best) <= kCountGoodEnough) break;
    if (too_many)
      fine = std::max(fine, h);
    else
      coarse = std::min(coarse, h);
    double next = h * std::sqrt(ratio);
    if (!(next > fine && next < coarse)) next = std::isfinite(coarse) && fine > 0.0 ? std::sqrt(fine * coarse) : next;
    if (next == h) break;
    h = next;
  }
  if (error(*best) > options.max_count_error)
    throw InputError(fmt::format("{}: no mesh size gives {} triangles within {:.1f}% (closest: {})", who, target,
                                 100.0 * options.max_count_error, best->triangles));
  block.mesh = extruded_block(best->planar, block.thickness_m, rows);
  block.size_bound_m = best->size_bound_mm * 1e-3;
  block.boundary_vertices = static_cast<int>(best->planar.boundary.size());
  block.wall_rows = rows;
  block.target_triangles = target;
  return block;
}

IndexedMesh mold_mesh(Mold mold, const MoldOptions& options) { return mold_block(mold, options).mesh; }

}  // namespace meltlab::datasets
