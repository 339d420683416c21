// Self-intersection test of the live triangles of a TriMesh with CGAL's box-intersection
// filter and exact predicates (Exact_predicates_inexact_constructions_kernel).
//
// Why not CGAL::Polygon_mesh_processing::self_intersections: in CGAL 5.5 it takes a
// halfedge graph (a Surface_mesh), and a broken mesh — non-manifold edges or vertices,
// inconsistent orientation, duplicate faces, references to dead vertices — cannot be
// loaded into one without changing its connectivity (add_face refuses such faces, and
// duplicating non-manifold vertices would turn faces that share a vertex into faces that
// merely touch, i.e. false positives). The validator must diagnose exactly such meshes, so
// it runs the same algorithm on the triangle soup instead: one bounding box per live
// triangle, CGAL::box_self_intersection_d for the candidate pairs, then the same exact
// tests as PMP's do_faces_intersect, with "shared vertex" meaning the same vertex slot.

#include <meltlab/sim/cgal/self_intersection.h>
#include <meltlab/core/error.h>

#include <CGAL/Bbox_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Intersections_3/Segment_3_Triangle_3.h>
#include <CGAL/Intersections_3/Triangle_3_Triangle_3.h>
#include <CGAL/box_intersection_d.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace meltlab::sim {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Segment = Kernel::Segment_3;
using Triangle3 = Kernel::Triangle_3;

// Box of one live triangle; info = position in the compact list of live triangles.
using Box =
    CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t, CGAL::Box_intersection_d::ID_FROM_BOX_ADDRESS>;

// Thrown from the box callback to stop the sweep once the cap is reached.
struct CapReached {};

// The live triangles as a soup: corner slot indices, their points, and their slots.
struct Soup {
  std::vector<Triangle> corners;
  std::vector<std::array<Point, 3>> points;
  std::vector<Index> slot;
};

template <class Real>
Soup live_soup(const TriMesh<Real>& m) {
  if (m.triangle_alive.size() != m.triangle.size())
    throw InvariantError(fmt::format("self_intersections: {} triangle slots but {} alive flags", m.triangle.size(),
                                     m.triangle_alive.size()));
  const std::size_t n_vertices = m.position.size();
  Soup s;
  const std::size_t n_live = m.live_triangle_count();
  s.corners.reserve(n_live);
  s.points.reserve(n_live);
  s.slot.reserve(n_live);
  for (std::size_t t = 0; t < m.triangle.size(); ++t) {
    if (!m.triangle_alive[t]) continue;
    const Triangle& tri = m.triangle[t];
    std::array<Point, 3> p;
    for (std::size_t k = 0; k < 3; ++k) {
      const Index v = tri[k];
      if (v < 0 || static_cast<std::size_t>(v) >= n_vertices)
        throw InvariantError(fmt::format(
            "self_intersections: live triangle {} uses vertex index {} (mesh has {} vertex slots)", t, v, n_vertices));
      const Vec3<Real>& q = m.position[static_cast<std::size_t>(v)];
      if (!q.allFinite())
        throw InvariantError(
            fmt::format("self_intersections: live triangle {} uses vertex v{} at a non-finite position", t, v));
      // float -> double is exact, so the predicates decide on the mesh's own coordinates.
      p[k] = Point(static_cast<double>(q.x()), static_cast<double>(q.y()), static_cast<double>(q.z()));
    }
    s.corners.push_back(tri);
    s.points.push_back(p);
    s.slot.push_back(static_cast<Index>(t));
  }
  return s;
}

// Exact test of two non-degenerate triangles of the soup, ignoring what they share by
// construction (the same as PMP's do_faces_intersect, on slot indices):
//  * three shared slots: the same triangle twice — they overlap;
//  * a shared edge: they intersect only if coplanar and folded onto each other;
//  * a shared vertex: they intersect if the edge opposite the vertex in one meets the other;
//  * nothing shared: plain triangle-triangle intersection.
bool triangles_intersect(const Triangle& a, const std::array<Point, 3>& pa, const Triangle& b,
                         const std::array<Point, 3>& pb) {
  int shared = 0;
  std::size_t ia = 0, ib = 0;  // one shared corner in a and in b
  std::array<bool, 3> a_shared{false, false, false}, b_shared{false, false, false};
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      if (a[i] == b[j]) {
        ++shared;
        a_shared[i] = b_shared[j] = true;
        ia = i;
        ib = j;
      }
  switch (shared) {
    case 0:
      return CGAL::do_intersect(Triangle3(pa[0], pa[1], pa[2]), Triangle3(pb[0], pb[1], pb[2]));
    case 1: {
      // Most candidate pairs of a fine closed mesh are fan neighbours: reject by boxes first.
      const Point& a1 = pa[(ia + 1) % 3];
      const Point& a2 = pa[(ia + 2) % 3];
      const Point& b1 = pb[(ib + 1) % 3];
      const Point& b2 = pb[(ib + 2) % 3];
      const CGAL::Bbox_3 box_a = pa[0].bbox() + pa[1].bbox() + pa[2].bbox();
      const CGAL::Bbox_3 box_b = pb[0].bbox() + pb[1].bbox() + pb[2].bbox();
      return (CGAL::do_overlap(box_a, b1.bbox() + b2.bbox()) &&
              CGAL::do_intersect(Triangle3(pa[0], pa[1], pa[2]), Segment(b1, b2))) ||
             (CGAL::do_overlap(box_b, a1.bbox() + a2.bbox()) &&
              CGAL::do_intersect(Triangle3(pb[0], pb[1], pb[2]), Segment(a1, a2)));
    }
    case 2: {
      const auto free_a =
          static_cast<std::size_t>(std::find(a_shared.begin(), a_shared.end(), false) - a_shared.begin());
      const auto free_b =
          static_cast<std::size_t>(std::find(b_shared.begin(), b_shared.end(), false) - b_shared.begin());
      const Point& e0 = pa[(free_a + 1) % 3];
      const Point& e1 = pa[(free_a + 2) % 3];
      return CGAL::coplanar(e0, e1, pa[free_a], pb[free_b]) &&
             CGAL::coplanar_orientation(e0, e1, pa[free_a], pb[free_b]) == CGAL::POSITIVE;
    }
    default:
      return true;  // the same three vertices: the triangles coincide
  }
}

}  // namespace

template <class Real>
SelfIntersectionReport self_intersections(const TriMesh<Real>& m, std::size_t max_pairs) {
  const std::size_t cap = std::max<std::size_t>(max_pairs, 1);
  const Soup soup = live_soup(m);
  SelfIntersectionReport report;
  auto record = [&](std::size_t i, std::size_t j) {
    const Index a = soup.slot[i], b = soup.slot[j];
    report.sample.emplace_back(std::min(a, b), std::max(a, b));
    if (report.sample.size() >= cap) throw CapReached{};
  };

  try {
    // Degenerate (exactly collinear) triangles have no plane to test against; like PMP,
    // report each as intersecting itself.
    std::vector<Box> boxes;
    boxes.reserve(soup.corners.size());
    for (std::size_t i = 0; i < soup.corners.size(); ++i) {
      const auto& p = soup.points[i];
      if (CGAL::collinear(p[0], p[1], p[2]))
        record(i, i);
      else
        boxes.emplace_back(p[0].bbox() + p[1].bbox() + p[2].bbox(), i);
    }
    std::vector<const Box*> box_ptr;
    box_ptr.reserve(boxes.size());
    for (const Box& b : boxes) box_ptr.push_back(&b);
    auto on_overlap = [&](const Box* x, const Box* y) {
      const std::size_t i = x->info(), j = y->info();
      if (triangles_intersect(soup.corners[i], soup.points[i], soup.corners[j], soup.points[j])) record(i, j);
    };
    // Cutoff as in PMP: below this many boxes the sweep switches to brute force.
    constexpr std::ptrdiff_t kCutoff = 2000;
    CGAL::box_self_intersection_d<CGAL::Sequential_tag>(box_ptr.begin(), box_ptr.end(), on_overlap, kCutoff);
  } catch (const CapReached&) {
    // the cap was reached; the pairs found so far are reported
  }
  std::sort(report.sample.begin(), report.sample.end());
  report.pairs = report.sample.size();
  report.intersects = report.pairs > 0;
  return report;
}

template SelfIntersectionReport self_intersections(const TriMesh<float>&, std::size_t);
template SelfIntersectionReport self_intersections(const TriMesh<double>&, std::size_t);

}  // namespace meltlab::sim
