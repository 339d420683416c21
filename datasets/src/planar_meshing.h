#pragma once
// Planar triangulations behind a plain interface (the only place that includes CGAL, in
// planar_meshing_cgal.cpp). Points are 2-D, triangles are counter-clockwise.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace meltlab::datasets::detail {

using Triangle2 = std::array<int, 3>;

/// Constrained Delaunay triangulation of the region bounded by `loops` (lists of indices
/// into `points`; a point is inside when it is enclosed an odd number of times, so an
/// outer loop and its holes define a polygon with holes). No vertices are added. Returns
/// CCW triangles indexing `points`. Throws InputError "<context>: ..." if loops cross or
/// two loop points coincide.
std::vector<Triangle2> constrained_triangles(const std::vector<Eigen::Vector2d>& points,
                                             const std::vector<std::vector<int>>& loops, const std::string& context);

/// Quality triangulation of the inside of a simple polygon.
struct PlanarMesh {
  std::vector<Eigen::Vector2d> V;  ///< vertices (the polygon's, then Steiner points)
  std::vector<Triangle2> F;        ///< CCW triangles
  std::vector<int> boundary;       ///< the boundary loop, CCW, after any constraint splits
};

/// CGAL::Delaunay_mesher_2 on the constrained Delaunay triangulation of `polygon` (simple,
/// CCW) with Delaunay_mesh_size_criteria_2(shape_bound, size_bound): no edge longer than
/// `size_bound` and no angle below about asin(sqrt(shape_bound)) degrees (20.6° for the
/// default 0.125). Throws InputError "<context>: ..." if the boundary does not come out
/// as one simple loop.
PlanarMesh refined_polygon_mesh(const std::vector<Eigen::Vector2d>& polygon, double size_bound,
                                const std::string& context, double shape_bound = 0.125);

}  // namespace meltlab::datasets::detail
