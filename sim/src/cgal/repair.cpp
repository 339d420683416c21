// Repair of a polygon soup into a closed, outward-oriented 2-manifold triangle mesh with
// CGAL's Polygon Mesh Processing. Pipeline (each step counted for RepairResult::actions):
//
//   1. soup repair: the steps of PMP::repair_polygon_soup, called one by one so that each
//      kind of change is counted (merge duplicate points, drop repeated corners, split
//      pinched polygons, drop polygons with < 3 corners, drop duplicate polygons, drop
//      unused points);
//   2. PMP::orient_polygon_soup: consistent orientation; cuts non-manifold edges and
//      duplicates non-manifold vertices (observed through its visitor);
//   3. PMP::polygon_soup_to_polygon_mesh into a Surface_mesh, PMP::triangulate_faces;
//   4. PMP::stitch_borders: re-joins border edges the orientation step had to cut, where
//      that is possible without breaking manifoldness;
//   5. every remaining hole is filled with PMP::triangulate_and_refine_hole (see below);
//      then closed parts that enclose no volume are dropped: a stray triangle or a fin cut
//      off a non-manifold edge comes out of hole filling as a two-sided sheet;
//   6. PMP::orient_to_bound_a_volume: outward orientation (inner shells of a hollow solid
//      inward). If parts cross each other their nesting is undefined and the result can
//      come out inside-out; then every part is oriented outward on its own;
//   7. extraction to IndexedMesh and the project's own validity check (check_topology).
//
// Orientation is reported as the net change per input polygon: orient_polygon_soup keeps
// the first polygon of each part and turns the others to match, so a cube with its first
// face flipped has five faces turned there and all six turned back in step 6; the action
// then reads "reversed orientation of 1 of 6 polygons", which is what happened to the input.
//
// Hole filling: triangulate_and_refine_hole, i.e. the minimal-area / max-dihedral patch of
// triangulate_hole, then refined so that its edge lengths match the hole's surroundings.
//   * Not plain triangulate_hole: a large hole would be closed by a few long triangles — a
//     rigid lid that the melt cycle cannot deform like the rest of the surface, and the worst
//     triangles of the mesh for the quality measures (Eq. 2.5).
//   * Not triangulate_refine_and_fair_hole: fairing invents shape. It bulges a planar cut
//     (the missing face of a cube, the flat base of a scanned block) into a dome, which
//     changes the volume that the melt experiments measure. Refinement only adds vertices
//     on the minimal patch, so a planar hole stays planar. (It also needs no sparse solver.)

// GCC's -Wnull-dereference fires inside CGAL's triangulation and soup-repair templates
// once they are inlined here (false positives in third-party code). It is a middle-end
// warning, so the system-header exemption does not apply; it is switched off for the
// includes only (the standard headers too: they are first read here), not for our code.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <meltlab/sim/cgal/repair.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/topology.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/bbox.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/compute_normal.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/repair_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/stitch_borders.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/exceptions.h>
#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <set>
#include <string_view>
#include <utility>
#pragma GCC diagnostic pop

namespace meltlab::sim {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Soup = std::vector<std::vector<std::size_t>>;

[[noreturn]] void refuse(const std::string& source, const std::string& why) {
  throw InputError(fmt::format("{}: cannot repair: {}", source, why));
}

std::string count_of(std::size_t n, std::string_view one, std::string_view many) {
  return fmt::format("{} {}", n, n == 1 ? one : many);
}

// Input checks CGAL would otherwise turn into undefined behaviour.
void check_input(const PolygonMesh& in, const std::string& source) {
  if (in.faces.empty()) refuse(source, "the mesh has no faces");
  for (std::size_t f = 0; f < in.faces.size(); ++f) {
    const PolygonFace& face = in.faces[f];
    if (!face.holes.empty())
      refuse(source, fmt::format("face {} has {}; faces with holes are not supported", f,
                                 count_of(face.holes.size(), "hole", "holes")));
    for (Index v : face.outer)
      if (v < 0 || static_cast<std::size_t>(v) >= in.V.size())
        refuse(source, fmt::format("face {} uses vertex index {} but the mesh has {} vertices", f, v, in.V.size()));
  }
  for (std::size_t v = 0; v < in.V.size(); ++v)
    if (!in.V[v].allFinite()) refuse(source, fmt::format("vertex v{} has a non-finite coordinate", v));
}

// Observes PMP::orient_polygon_soup. It is copied by CGAL, so it only holds pointers.
struct OrientationObserver : PMP::Default_orientation_visitor {
  std::vector<std::uint8_t>* reversed = nullptr;                               // per polygon, toggled
  std::set<std::pair<std::size_t, std::size_t>>* nonmanifold_edges = nullptr;  // reported once per polygon on it
  std::size_t* nonmanifold_vertices = nullptr;
  std::size_t* vertex_copies = nullptr;

  void non_manifold_edge(std::size_t a, std::size_t b, std::size_t) { nonmanifold_edges->insert(std::minmax(a, b)); }
  void non_manifold_vertex(std::size_t, std::size_t) { ++*nonmanifold_vertices; }
  void duplicated_vertex(std::size_t, std::size_t) { ++*vertex_copies; }
  void polygon_orientation_reversed(std::size_t p) { (*reversed)[p] ^= 1; }
};

using SourceMap = Mesh::Property_map<Mesh::Face_index, std::int64_t>;

// Observes PMP::triangulate_faces: every triangle inherits the soup polygon it came from.
struct SourceTracker : PMP::Triangulate_faces::Default_visitor<Mesh> {
  SourceMap source;
  std::int64_t* current = nullptr;

  void before_subface_creations(Mesh::Face_index f) { *current = source[f]; }
  void after_subface_created(Mesh::Face_index f) { source[f] = *current; }
};

using HoleMap = Mesh::Property_map<Mesh::Face_index, std::int64_t>;

// The connected components of a closed, garbage-free triangle mesh and their volumes.
struct Parts {
  std::vector<std::size_t> of_face;  ///< component id by face index
  std::vector<double> volume;        ///< signed, positive if outward oriented, mesh units³
  std::vector<double> diagonal;      ///< of the component's bounding box, mesh units
};

Parts parts_of(Mesh& mesh) {
  auto component_of = mesh.add_property_map<Mesh::Face_index, std::size_t>("f:meltlab_component", 0).first;
  const std::size_t n = PMP::connected_components(mesh, component_of);
  Parts parts;
  parts.of_face.resize(mesh.number_of_faces());
  std::vector<double> six_volume(n, 0.0);
  std::vector<Point> origin(n);                // each volume is summed about a vertex of its own part,
  std::vector<std::uint8_t> has_origin(n, 0);  // which keeps the rounding small
  std::vector<CGAL::Bbox_3> box(n);
  for (Mesh::Face_index f : mesh.faces()) {
    const std::size_t c = component_of[f];
    parts.of_face[f.idx()] = c;
    std::array<Point, 3> p;
    std::size_t k = 0;
    for (Mesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) p[k++] = mesh.point(v);
    if (!has_origin[c]) {
      origin[c] = p[0];
      has_origin[c] = 1;
    }
    six_volume[c] += CGAL::determinant(p[0] - origin[c], p[1] - origin[c], p[2] - origin[c]);
    box[c] += p[0].bbox() + p[1].bbox() + p[2].bbox();
  }
  mesh.remove_property_map(component_of);
  for (std::size_t c = 0; c < n; ++c) {
    parts.volume.push_back(six_volume[c] / 6.0);
    const double dx = box[c].xmax() - box[c].xmin(), dy = box[c].ymax() - box[c].ymin(),
                 dz = box[c].zmax() - box[c].zmin();
    parts.diagonal.push_back(std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  return parts;
}

// True if |volume| is lost in rounding: at most this fraction of the cube of the bounding-
// box diagonal (far above the rounding of the sum, far below any real solid's volume).
bool is_flat(double volume, double diagonal) {
  constexpr double kFlatVolumeFraction = 1e-12;
  return std::abs(volume) <= kFlatVolumeFraction * diagonal * diagonal * diagonal;
}

// True if the closed mesh encloses a positive volume that is not lost in rounding.
bool encloses_volume(Mesh& mesh) {
  const Parts parts = parts_of(mesh);
  const CGAL::Bbox_3 box = PMP::bbox(mesh);
  const double dx = box.xmax() - box.xmin(), dy = box.ymax() - box.ymin(), dz = box.zmax() - box.zmin();
  double volume = 0.0;
  for (double v : parts.volume) volume += v;
  return volume > 0.0 && !is_flat(volume, std::sqrt(dx * dx + dy * dy + dz * dz));
}

// True if polygon `f`, projected onto the plane orthogonal to its normal, is a simple
// polygon with some room to spare. triangulate_faces triangulates polygons of 5 or more
// corners with a constrained Delaunay triangulation of exactly that projection, with exact
// constraint intersections; for a polygon whose projection crosses itself that cascades
// (the intersection points are constructed in 3D and need not lie in the plane) and can run
// for hours. Such polygons go through hole filling instead. Quads are split directly.
bool clearly_simple_polygon(const Mesh& mesh, Mesh::Face_index f) {
  // Edges closer than this fraction of the polygon's extent count as touching.
  constexpr double kSeparationFraction = 1e-9;
  const Kernel::Vector_3 normal = PMP::compute_face_normal(f, mesh);
  if (normal == CGAL::NULL_VECTOR) return false;
  // Orthonormal basis (u, v) of the projection plane.
  const double nx = normal.x(), ny = normal.y(), nz = normal.z();
  Eigen::Vector3d n(nx, ny, nz);
  n.normalize();
  Eigen::Vector3d u = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  u = (u - n * n.dot(u)).normalized();
  const Eigen::Vector3d v = n.cross(u);
  std::vector<Eigen::Vector2d> q;
  for (Mesh::Vertex_index w : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
    const Point& p = mesh.point(w);
    const Eigen::Vector3d x(p.x(), p.y(), p.z());
    q.emplace_back(x.dot(u), x.dot(v));
  }
  const std::size_t n_corners = q.size();
  Eigen::AlignedBox2d box;
  for (const auto& x : q) box.extend(x);
  const double margin = kSeparationFraction * box.diagonal().norm();
  auto cross = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
  auto point_segment = [](const Eigen::Vector2d& x, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double t = std::clamp((x - a).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
    return (a + t * ab - x).norm();
  };
  auto segments_cross = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                            const Eigen::Vector2d& d) {
    const double o1 = cross(b - a, c - a), o2 = cross(b - a, d - a), o3 = cross(d - c, a - c), o4 = cross(d - c, b - c);
    return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0));
  };
  for (std::size_t i = 0; i < n_corners; ++i) {
    const Eigen::Vector2d& a = q[i];
    const Eigen::Vector2d& b = q[(i + 1) % n_corners];
    const Eigen::Vector2d& before = q[(i + n_corners - 1) % n_corners];
    // An edge folding back onto the previous one.
    if (std::abs(cross(b - a, before - a)) <= margin * (b - a).norm() && (b - a).dot(before - a) > 0) return false;
    for (std::size_t j = i + 2; j < n_corners; ++j) {
      if (i == 0 && j == n_corners - 1) continue;  // adjacent through corner 0
      const Eigen::Vector2d& c = q[j];
      const Eigen::Vector2d& d = q[(j + 1) % n_corners];
      if (segments_cross(a, b, c, d) || point_segment(a, c, d) <= margin || point_segment(b, c, d) <= margin ||
          point_segment(c, a, b) <= margin || point_segment(d, a, b) <= margin)
        return false;
    }
  }
  return true;
}

// A directed edge of every face, to tell afterwards whether the face was reversed.
std::vector<std::pair<Mesh::Vertex_index, Mesh::Vertex_index>> face_directions(const Mesh& mesh) {
  std::vector<std::pair<Mesh::Vertex_index, Mesh::Vertex_index>> d(mesh.number_of_faces());
  for (Mesh::Face_index f : mesh.faces()) {
    const Mesh::Halfedge_index h = mesh.halfedge(f);
    d[f.idx()] = {mesh.source(h), mesh.target(h)};
  }
  return d;
}

bool face_has_direction(const Mesh& mesh, Mesh::Face_index f, std::pair<Mesh::Vertex_index, Mesh::Vertex_index> e) {
  for (Mesh::Halfedge_index h : CGAL::halfedges_around_face(mesh.halfedge(f), mesh))
    if (mesh.source(h) == e.first && mesh.target(h) == e.second) return true;
  return false;
}

IndexedMesh indexed_mesh(const Mesh& mesh) {
  IndexedMesh out;
  out.V.reserve(mesh.number_of_vertices());
  for (Mesh::Vertex_index v : mesh.vertices()) {
    const Point& p = mesh.point(v);
    out.V.emplace_back(p.x(), p.y(), p.z());
  }
  out.F.reserve(mesh.number_of_faces());
  for (Mesh::Face_index f : mesh.faces()) {
    Triangle t{};
    std::size_t k = 0;
    for (Mesh::Vertex_index v : CGAL::vertices_around_face(mesh.halfedge(f), mesh))
      t[k++] = static_cast<Index>(v.idx());
    out.F.push_back(t);
  }
  return out;
}

using Actions = std::vector<std::string>;

/// Step 1: the steps of PMP::repair_polygon_soup, in its order, each counted.
void repair_soup(std::vector<Point>& points, Soup& polygons, Actions& actions, const std::string& source) {
  const Kernel traits;
  const std::size_t merged_points = PMP::merge_duplicate_points_in_polygon_soup(points, polygons);
  // These three are CGAL 5.5 internals of repair_polygon_soup; called directly for counts.
  const std::size_t simplified = PMP::internal::simplify_polygons_in_polygon_soup(points, polygons, traits);
  const std::size_t pinched_parts = PMP::internal::split_pinched_polygons_in_polygon_soup(points, polygons, traits);
  const std::size_t invalid = PMP::internal::remove_invalid_polygons_in_polygon_soup(points, polygons);
  const std::size_t duplicates = PMP::merge_duplicate_polygons_in_polygon_soup(points, polygons);
  const std::size_t isolated = PMP::remove_isolated_points_in_polygon_soup(points, polygons);
  if (merged_points) actions.push_back("merged " + count_of(merged_points, "duplicate point", "duplicate points"));
  if (simplified) actions.push_back("removed repeated corners from " + count_of(simplified, "polygon", "polygons"));
  if (pinched_parts)
    actions.push_back(fmt::format("split pinched polygons (a corner visited twice) into {} more",
                                  count_of(pinched_parts, "polygon", "polygons")));
  if (invalid)
    actions.push_back("removed " + count_of(invalid, "degenerate polygon", "degenerate polygons") +
                      " with fewer than 3 distinct corners");
  if (duplicates) actions.push_back("removed " + count_of(duplicates, "duplicate polygon", "duplicate polygons"));
  if (isolated) actions.push_back("dropped " + count_of(isolated, "unused vertex", "unused vertices"));
  if (polygons.empty()) refuse(source, "no polygon has 3 distinct corners");
}

/// Step 2: consistent orientation, non-manifold edges cut and vertices split. Returns, per
/// polygon, whether it was reversed.
std::vector<std::uint8_t> orient_soup(std::vector<Point>& points, Soup& polygons, Actions& actions,
                                      const std::string& source) {
  std::vector<std::uint8_t> reversed_in_soup(polygons.size(), 0);
  std::set<std::pair<std::size_t, std::size_t>> nonmanifold_edges;
  std::size_t nonmanifold_vertices = 0, vertex_copies = 0;
  OrientationObserver observer;
  observer.reversed = &reversed_in_soup;
  observer.nonmanifold_edges = &nonmanifold_edges;
  observer.nonmanifold_vertices = &nonmanifold_vertices;
  observer.vertex_copies = &vertex_copies;
  PMP::orient_polygon_soup(points, polygons, CGAL::parameters::visitor(observer));
  if (!nonmanifold_edges.empty())
    actions.push_back("cut " + count_of(nonmanifold_edges.size(), "non-manifold edge", "non-manifold edges"));
  if (nonmanifold_vertices || vertex_copies) {
    std::string line = "split " + count_of(nonmanifold_vertices, "non-manifold vertex", "non-manifold vertices");
    if (vertex_copies != nonmanifold_vertices)
      line += fmt::format(" ({} added)", count_of(vertex_copies, "copy", "copies"));
    actions.push_back(line);
  }
  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons))
    refuse(source, "the polygons cannot be made into a manifold surface");
  return reversed_in_soup;
}

/// Step 3: the soup as a Surface_mesh, triangulated; every face remembers its soup polygon
/// in the returned property map (face i = polygon i before triangulation).
SourceMap triangulated_mesh(const std::vector<Point>& points, const Soup& polygons, Mesh& mesh,
                            const std::string& source) {
  const std::size_t n_polygons = polygons.size();
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);
  if (mesh.number_of_faces() != n_polygons || mesh.number_of_vertices() != points.size())
    throw InvariantError(fmt::format("{}: repair: the soup of {} polygons became a mesh of {} faces", source,
                                     n_polygons, mesh.number_of_faces()));
  SourceMap source_of = mesh.add_property_map<Mesh::Face_index, std::int64_t>("f:meltlab_source", -1).first;
  for (Mesh::Face_index f : mesh.faces()) source_of[f] = static_cast<std::int64_t>(f.idx());  // face i = polygon i
  std::int64_t current_source = -1;
  SourceTracker tracker;
  tracker.source = source_of;
  tracker.current = &current_source;
  // Polygons that are not clearly simple go through hole filling (no new points), the rest
  // through the constrained Delaunay triangulation of triangulate_faces (see
  // clearly_simple_polygon for why).
  std::vector<Mesh::Face_index> tangled;
  for (Mesh::Face_index f : mesh.faces())
    if (mesh.degree(f) > 4 && !clearly_simple_polygon(mesh, f)) tangled.push_back(f);
  std::size_t untriangulated = 0;
  for (Mesh::Face_index f : tangled)
    if (!PMP::triangulate_face(f, mesh, CGAL::parameters::use_delaunay_triangulation(false).visitor(tracker)))
      ++untriangulated;
  if (untriangulated > 0)
    refuse(source, count_of(untriangulated, "polygon", "polygons") +
                       " cannot be triangulated (self-crossing or enclosing no area)");
  if (!PMP::triangulate_faces(mesh, CGAL::parameters::visitor(tracker))) {
    std::size_t left = 0;
    for (Mesh::Face_index f : mesh.faces())
      if (mesh.degree(f) != 3) ++left;
    refuse(source,
           count_of(left, "polygon", "polygons") + " cannot be triangulated (self-crossing or enclosing no area)");
  }
  return source_of;
}

/// Steps 4-5: stitch what can be stitched, fill every remaining hole. Patch faces remember
/// their hole (returned map) and soup vertices are marked (`v:meltlab_from_soup`), so that
/// the fill can be reported for what is kept after drop_flat_parts.
HoleMap close_holes(Mesh& mesh, Actions& actions, const std::string& source) {
  const std::size_t stitched = PMP::stitch_borders(mesh);
  if (stitched) actions.push_back("stitched " + count_of(stitched, "border edge", "border edges"));
  HoleMap hole_of = mesh.add_property_map<Mesh::Face_index, std::int64_t>("f:meltlab_hole", -1).first;
  auto from_soup = mesh.add_property_map<Mesh::Vertex_index, std::uint8_t>("v:meltlab_from_soup", 0).first;
  for (Mesh::Vertex_index v : mesh.vertices()) from_soup[v] = 1;
  std::vector<Mesh::Halfedge_index> holes;
  PMP::extract_boundary_cycles(mesh, std::back_inserter(holes));
  for (std::size_t k = 0; k < holes.size(); ++k) {
    if (!mesh.is_border(holes[k])) continue;  // defensive: closed by an earlier patch
    std::vector<Mesh::Face_index> patch;
    PMP::triangulate_and_refine_hole(mesh, holes[k], std::back_inserter(patch), CGAL::Emptyset_iterator());
    for (Mesh::Face_index f : patch) hole_of[f] = static_cast<std::int64_t>(k);
  }
  if (!CGAL::is_closed(mesh)) {
    std::vector<Mesh::Halfedge_index> left;
    PMP::extract_boundary_cycles(mesh, std::back_inserter(left));
    refuse(source, fmt::format("{} of {} could not be filled", left.size(), count_of(holes.size(), "hole", "holes")));
  }
  mesh.collect_garbage();  // PMP's face index maps assume contiguous indices
  return hole_of;
}

/// Step 5b: drop closed parts that enclose no volume (a stray triangle closed by its own
/// back side, a fin cut off a non-manifold edge, a two-sided sheet).
void drop_flat_parts(Mesh& mesh, const SourceMap& source_of, Actions& actions, const std::string& source) {
  const Parts parts = parts_of(mesh);
  std::vector<std::uint8_t> flat(parts.volume.size(), 0);
  for (std::size_t c = 0; c < flat.size(); ++c) flat[c] = is_flat(parts.volume[c], parts.diagonal[c]);
  const auto n_flat = static_cast<std::size_t>(std::count(flat.begin(), flat.end(), 1));
  if (n_flat == flat.size()) refuse(source, "the closed surface encloses no volume");
  if (n_flat == 0) return;
  std::set<std::int64_t> dropped_polygons;
  std::vector<Mesh::Face_index> doomed;
  for (Mesh::Face_index f : mesh.faces())
    if (flat[parts.of_face[f.idx()]]) {
      doomed.push_back(f);
      if (source_of[f] >= 0) dropped_polygons.insert(source_of[f]);
    }
  // Whole closed components go, so nothing left behind becomes non-manifold; vertices
  // left without faces are removed by remove_face.
  for (Mesh::Face_index f : doomed) CGAL::Euler::remove_face(mesh.halfedge(f), mesh);
  mesh.collect_garbage();
  actions.push_back(fmt::format("removed {} enclosing no volume ({} of the input)", count_of(n_flat, "part", "parts"),
                                count_of(dropped_polygons.size(), "polygon", "polygons")));
}

/// The hole fill as far as it is kept: holes, patch triangles and new vertices.
void report_filled_holes(const Mesh& mesh, const HoleMap& hole_of, Actions& actions) {
  const auto from_soup = mesh.property_map<Mesh::Vertex_index, std::uint8_t>("v:meltlab_from_soup").first;
  std::set<std::int64_t> filled;
  std::size_t patch_faces = 0, new_vertices = 0;
  for (Mesh::Face_index f : mesh.faces())
    if (hole_of[f] >= 0) {
      filled.insert(hole_of[f]);
      ++patch_faces;
    }
  for (Mesh::Vertex_index v : mesh.vertices())
    if (!from_soup[v]) ++new_vertices;
  if (filled.empty()) return;
  std::string line = fmt::format("filled {} with {}", count_of(filled.size(), "hole", "holes"),
                                 count_of(patch_faces, "triangle", "triangles"));
  if (new_vertices) line += fmt::format(" and {}", count_of(new_vertices, "new vertex", "new vertices"));
  actions.push_back(line);
}

/// Step 6: outward orientation, reported as the net orientation change of each input polygon.
void orient_outward(Mesh& mesh, const SourceMap& source_of, const std::vector<std::uint8_t>& reversed_in_soup,
                    Actions& actions) {
  const auto before = face_directions(mesh);
  bool oriented = true;
  try {
    PMP::orient_to_bound_a_volume(mesh);
  } catch (const CGAL::Failure_exception&) {
    // Only with CGAL's checks on (no NDEBUG): its outward test asserts that the surface
    // does not cross itself near the topmost vertex, before changing anything. Without the
    // checks the test just answers at random there, which the volume check below catches.
    oriented = false;
  }
  if (!oriented || !encloses_volume(mesh)) {
    // Parts that cross each other have no defined nesting, and orient_to_bound_a_volume can
    // then leave the whole inside-out; orient every part outward on its own instead.
    const Parts parts = parts_of(mesh);
    std::vector<Mesh::Face_index> inside_out;
    for (Mesh::Face_index f : mesh.faces())
      if (parts.volume[parts.of_face[f.idx()]] < 0.0) inside_out.push_back(f);
    PMP::reverse_face_orientations(inside_out, mesh);
  }
  const std::size_t n_polygons = reversed_in_soup.size();
  std::vector<std::int8_t> net_reversed(n_polygons, -1);
  for (Mesh::Face_index f : mesh.faces()) {
    const std::int64_t p = source_of[f];
    if (p < 0) continue;  // a hole patch
    const bool flipped_now = !face_has_direction(mesh, f, before[f.idx()]);
    net_reversed[static_cast<std::size_t>(p)] =
        static_cast<std::int8_t>(flipped_now != (reversed_in_soup[static_cast<std::size_t>(p)] != 0));
  }
  const auto n_reversed = static_cast<std::size_t>(std::count(net_reversed.begin(), net_reversed.end(), 1));
  const auto n_kept = n_polygons - static_cast<std::size_t>(std::count(net_reversed.begin(), net_reversed.end(), -1));
  if (n_reversed > 0 && n_reversed == n_kept)
    actions.push_back(fmt::format("reversed orientation of all {} (the input was inside-out)",
                                  count_of(n_kept, "polygon", "polygons")));
  else if (n_reversed > 0)
    actions.push_back(
        fmt::format("reversed orientation of {} of {}", n_reversed, count_of(n_kept, "polygon", "polygons")));
}

/// The pipeline of the file comment, one stage per step.
RepairResult repair(const PolygonMesh& in, const std::string& source) {
  RepairResult result;
  std::vector<Point> points;
  points.reserve(in.V.size());
  for (const auto& p : in.V) points.emplace_back(p.x(), p.y(), p.z());
  Soup polygons;
  polygons.reserve(in.faces.size());
  for (const PolygonFace& f : in.faces) polygons.emplace_back(f.outer.begin(), f.outer.end());

  repair_soup(points, polygons, result.actions, source);
  const std::vector<std::uint8_t> reversed_in_soup = orient_soup(points, polygons, result.actions, source);
  Mesh mesh;
  const SourceMap source_of = triangulated_mesh(points, polygons, mesh, source);
  const HoleMap hole_of = close_holes(mesh, result.actions, source);
  drop_flat_parts(mesh, source_of, result.actions, source);
  report_filled_holes(mesh, hole_of, result.actions);
  orient_outward(mesh, source_of, reversed_in_soup, result.actions);

  // Step 7: the result, checked with the project's own definition of a valid solid.
  result.mesh = indexed_mesh(mesh);
  const TriMesh<double> check = TriMesh<double>::from_indexed(result.mesh);
  const TopologyReport topo = check_topology(check);
  if (!topo.valid())
    refuse(source, topo.problems.empty() ? std::string("the result is not a valid closed solid")
                                         : topo.problems.front().describe() + " (in the repaired mesh)");
  if (!encloses_volume(mesh)) refuse(source, "the closed surface encloses no volume");
  return result;
}

}  // namespace

RepairResult repair_closed_solid(const PolygonMesh& in, const std::string& source) {
  check_input(in, source);
  try {
    return repair(in, source);
  } catch (const CGAL::Failure_exception& e) {
    // Only reachable in builds with CGAL's checks on (no NDEBUG): a precondition of a
    // CGAL step failed on this input.
    refuse(source, fmt::format("CGAL {} failed ({})", e.library(), e.expression()));
  }
}

}  // namespace meltlab::sim
