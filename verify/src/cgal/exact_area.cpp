// compare_regions_exact: the P measure from exact polygon Boolean operations (CGAL
// Polygon_set_2 over Exact_predicates_exact_constructions_kernel). Kept in src/cgal so that
// CGAL's compile options stay out of the other translation units.
//
// A Region is read with even-odd semantics over all its loops (the same rule
// rasterize_region samples), which is exactly "outers minus holes" for well-formed regions
// and needs no assumption about how holes were assigned to outers. Loops that touch
// themselves at a vertex (pinched pixel corners of region_from_mask, iso-valued corners of
// region_from_image) are split there into simple loops; every simple loop is oriented
// counter-clockwise and the region is the aggregated symmetric difference (XOR) of all of
// them. Areas of A, B and A∩B are summed exactly and converted to double at the end.

#include <meltlab/verify/metrics.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_2.h>
#include <CGAL/Polygon_set_2.h>
#include <CGAL/Polygon_with_holes_2.h>

#include <iterator>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace meltlab::verify {

namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = K::Point_2;
using Poly = CGAL::Polygon_2<K>;
using PolySet = CGAL::Polygon_set_2<K>;
using FT = K::FT;

// Splits a closed loop at repeated vertices into loops without repeated vertices.
void split_loop(const std::vector<Vec2d>& loop, std::vector<std::vector<Vec2d>>& out) {
  std::vector<Vec2d> stack;
  std::map<std::pair<double, double>, std::size_t> pos;  // vertex -> index in stack
  auto push = [&](const Vec2d& p) {
    const auto key = std::make_pair(p.x(), p.y());
    auto it = pos.find(key);
    if (it == pos.end()) {
      pos.emplace(key, stack.size());
      stack.push_back(p);
      return;
    }
    // Close the sub-loop stack[it->second ..] and keep its first vertex on the stack.
    const std::size_t from = it->second;
    std::vector<Vec2d> sub(stack.begin() + static_cast<std::ptrdiff_t>(from), stack.end());
    for (std::size_t i = from + 1; i < stack.size(); ++i) pos.erase(std::make_pair(stack[i].x(), stack[i].y()));
    stack.resize(from + 1);
    if (sub.size() >= 3) out.push_back(std::move(sub));
  };
  for (const Vec2d& p : loop) push(p);
  if (!stack.empty()) push(stack.front());  // closing edge back to the start
  // After closing, the stack holds just the start vertex.
}

std::vector<Poly> simple_loops(const Region& r) {
  std::vector<std::vector<Vec2d>> loops;
  for (const Polygon& p : r) {
    split_loop(p.outer, loops);
    for (const auto& h : p.holes) split_loop(h, loops);
  }
  std::vector<Poly> polys;
  polys.reserve(loops.size());
  for (const auto& l : loops) {
    Poly pg;
    for (const Vec2d& v : l) pg.push_back(Point(v.x(), v.y()));  // doubles convert exactly
    const CGAL::Orientation o = pg.orientation();
    if (o == CGAL::COLLINEAR) continue;  // zero area
    if (!pg.is_simple())
      throw std::invalid_argument("compare_regions_exact: region has a self-intersecting loop (" +
                                  std::to_string(l.size()) + " vertices)");
    if (o == CGAL::CLOCKWISE) pg.reverse_orientation();
    polys.push_back(std::move(pg));
  }
  return polys;
}

PolySet to_set(const Region& r) {
  PolySet s;
  std::vector<Poly> polys = simple_loops(r);
  if (!polys.empty()) s.symmetric_difference(polys.begin(), polys.end());
  return s;
}

FT set_area(const PolySet& s) {
  std::vector<CGAL::Polygon_with_holes_2<K>> pwhs;
  s.polygons_with_holes(std::back_inserter(pwhs));
  FT a = 0;
  for (const auto& p : pwhs) {
    a += CGAL::abs(p.outer_boundary().area());
    for (auto h = p.holes_begin(); h != p.holes_end(); ++h) a -= CGAL::abs(h->area());
  }
  return a;
}

}  // namespace

AreaComparison compare_regions_exact(const Region& photo, const Region& render) {
  const PolySet a = to_set(photo), b = to_set(render);
  PolySet i;
  i.intersection(a, b);
  const FT area_a = set_area(a), area_b = set_area(b), area_i = set_area(i);
  AreaComparison c;
  c.S_I = CGAL::to_double(area_i);
  c.S_A = CGAL::to_double(area_a - area_i);
  c.S_B = CGAL::to_double(area_b - area_i);
  const FT uni = area_a + area_b - area_i;
  if (CGAL::is_positive(uni)) {
    c.P = CGAL::to_double((area_a + area_b - 2 * area_i) / uni);
    c.IoU = CGAL::to_double(area_i / uni);
    c.Dice = CGAL::to_double(2 * area_i / (area_a + area_b));
  } else {
    c.P = 0;
    c.IoU = 1;
    c.Dice = 1;
  }
  return c;
}

}  // namespace meltlab::verify
