// CGAL 2-D constrained Delaunay triangulation and Delaunay refinement (planar_meshing.h).
// Kept in this one translation unit: including CGAL costs ~25 s of compile time.

// GCC's -Wnull-dereference fires inside Boost.MultiIndex (used by CGAL's mesher queue) once
// it is inlined here: a middle-end false positive in third-party code, which the
// system-header exemption does not cover. Switched off for the includes only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <meltlab/core/error.h>

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <fmt/format.h>

#include <deque>
#include <map>

#include "planar_meshing.h"
#pragma GCC diagnostic pop

namespace meltlab::datasets::detail {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

// ---- constrained triangulation with nesting levels (no Steiner points) ----

struct FaceNesting {
  int level = -1;  // number of constraint crossings from the infinite face; odd = inside
};
using CtVb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using CtFbb = CGAL::Triangulation_face_base_with_info_2<FaceNesting, K>;
using CtFb = CGAL::Constrained_triangulation_face_base_2<K, CtFbb>;
using CtTds = CGAL::Triangulation_data_structure_2<CtVb, CtFb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, CtTds, CGAL::Exact_predicates_tag>;

// Flood fill: faces reachable without crossing a constraint share a level; crossing one
// adds 1 (CGAL's polygon_triangulation example).
void mark_nesting(Cdt& cdt) {
  for (auto f : cdt.all_face_handles()) f->info().level = -1;
  std::deque<std::pair<Cdt::Face_handle, int>> border{{cdt.infinite_face(), 0}};
  while (!border.empty()) {
    auto [start, level] = border.front();
    border.pop_front();
    if (start->info().level != -1) continue;
    std::deque<Cdt::Face_handle> queue{start};
    start->info().level = level;
    while (!queue.empty()) {
      Cdt::Face_handle f = queue.front();
      queue.pop_front();
      for (int i = 0; i < 3; ++i) {
        Cdt::Face_handle n = f->neighbor(i);
        if (n->info().level != -1) continue;
        if (cdt.is_constrained(Cdt::Edge(f, i))) {
          border.emplace_back(n, level + 1);
        } else {
          n->info().level = level;
          queue.push_back(n);
        }
      }
    }
  }
}

// ---- Delaunay refinement ----

using MVb = CGAL::Triangulation_vertex_base_with_info_2<int, K, CGAL::Delaunay_mesh_vertex_base_2<K>>;
using MFb = CGAL::Delaunay_mesh_face_base_2<K>;
using MTds = CGAL::Triangulation_data_structure_2<MVb, MFb>;
using MeshCdt = CGAL::Constrained_Delaunay_triangulation_2<K, MTds>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<MeshCdt>;
using Mesher = CGAL::Delaunay_mesher_2<MeshCdt, Criteria>;

}  // namespace

std::vector<Triangle2> constrained_triangles(const std::vector<Eigen::Vector2d>& points,
                                             const std::vector<std::vector<int>>& loops, const std::string& context) {
  Cdt cdt;
  std::map<int, Cdt::Vertex_handle> handle;
  for (const auto& loop : loops) {
    for (int i : loop) {
      if (handle.count(i)) continue;
      const auto& p = points.at(static_cast<std::size_t>(i));
      const std::size_t before = cdt.number_of_vertices();
      Cdt::Vertex_handle v = cdt.insert(K::Point_2(p.x(), p.y()));
      if (cdt.number_of_vertices() == before)
        throw InputError(fmt::format("{}: loop vertex {} coincides with vertex {}", context, i, v->info()));
      v->info() = i;
      handle[i] = v;
    }
  }
  const std::size_t loop_points = handle.size();
  for (const auto& loop : loops)
    for (std::size_t k = 0; k < loop.size(); ++k)
      cdt.insert_constraint(handle[loop[k]], handle[loop[(k + 1) % loop.size()]]);
  if (cdt.number_of_vertices() != loop_points) throw InputError(fmt::format("{}: its loops cross each other", context));
  mark_nesting(cdt);
  std::vector<Triangle2> out;
  for (auto f : cdt.finite_face_handles()) {
    if (f->info().level % 2 != 1) continue;
    out.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  }
  return out;
}

PlanarMesh refined_polygon_mesh(const std::vector<Eigen::Vector2d>& polygon, double size_bound,
                                const std::string& context, double shape_bound) {
  MeshCdt cdt;
  std::vector<MeshCdt::Vertex_handle> vh;
  vh.reserve(polygon.size());
  for (const auto& p : polygon) vh.push_back(cdt.insert(MeshCdt::Point(p.x(), p.y())));
  if (cdt.number_of_vertices() != polygon.size())
    throw InputError(fmt::format("{}: outline has coincident points", context));
  for (std::size_t k = 0; k < vh.size(); ++k) cdt.insert_constraint(vh[k], vh[(k + 1) % vh.size()]);
  if (cdt.number_of_vertices() != polygon.size()) throw InputError(fmt::format("{}: outline crosses itself", context));

  Mesher mesher(cdt);
  mesher.set_criteria(Criteria(shape_bound, size_bound));
  mesher.refine_mesh();  // no seeds: the domain is the bounded region inside the outline

  PlanarMesh out;
  for (auto v : cdt.finite_vertex_handles()) v->info() = -1;
  auto index = [&](MeshCdt::Vertex_handle v) {
    if (v->info() < 0) {
      v->info() = static_cast<int>(out.V.size());
      out.V.emplace_back(CGAL::to_double(v->point().x()), CGAL::to_double(v->point().y()));
    }
    return v->info();
  };
  // Polygon vertices first, in order, so the boundary starts at polygon[0].
  for (const auto& v : vh) index(v);
  std::map<int, int> next;  // boundary: start vertex -> end vertex, CCW
  std::size_t boundary_edges = 0;
  for (auto f : cdt.finite_face_handles()) {
    if (!f->is_in_domain()) continue;
    out.F.push_back({index(f->vertex(0)), index(f->vertex(1)), index(f->vertex(2))});
    for (int i = 0; i < 3; ++i) {
      const auto n = f->neighbor(i);
      if (!cdt.is_infinite(n) && n->is_in_domain()) continue;
      // Edge i is opposite vertex i and runs ccw(i) -> cw(i) in this CCW face.
      const int a = index(f->vertex(MeshCdt::ccw(i))), b = index(f->vertex(MeshCdt::cw(i)));
      if (!next.emplace(a, b).second)
        throw InputError(fmt::format("{}: the meshed outline touches itself at a vertex", context));
      ++boundary_edges;
    }
  }
  int v = 0;
  do {
    out.boundary.push_back(v);
    auto it = next.find(v);
    if (it == next.end()) throw InputError(fmt::format("{}: the meshed outline is not closed", context));
    v = it->second;
  } while (v != 0 && out.boundary.size() <= boundary_edges);
  if (out.boundary.size() != boundary_edges)
    throw InputError(fmt::format("{}: the meshed outline is not one simple loop ({} of {} boundary edges)", context,
                                 out.boundary.size(), boundary_edges));
  // Vertices only reachable through faces outside the domain would be orphans: there are
  // none for a simple polygon, but make sure.
  if (out.V.size() != cdt.number_of_vertices()) {
    std::vector<char> used(out.V.size(), 0);
    for (const auto& t : out.F)
      for (int i : t) used[static_cast<std::size_t>(i)] = 1;
    for (char u : used)
      if (!u) throw InputError(fmt::format("{}: meshing left an unused vertex", context));
  }
  return out;
}

}  // namespace meltlab::datasets::detail
