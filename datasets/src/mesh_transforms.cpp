#include <meltlab/datasets/mesh_transforms.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include <cmath>

#include "checks.h"
#include "planar_meshing.h"

namespace meltlab::datasets {

using sim::Index;
using sim::IndexedMesh;
using sim::PolygonMesh;
using sim::Vec3;

namespace {

void require_finite_offset(const Eigen::Vector3d& offset) {
  if (!offset.allFinite())
    throw InputError(fmt::format("translated: offset ({}, {}, {}) is not finite", offset.x(), offset.y(), offset.z()));
}

std::vector<Index> shifted(const std::vector<Index>& loop, Index by) {
  std::vector<Index> out(loop);
  for (auto& v : out) v += by;
  return out;
}

}  // namespace

IndexedMesh scaled(const IndexedMesh& mesh, double factor) {
  detail::require_positive_length("scaled", "factor", factor);
  IndexedMesh out = mesh;
  for (auto& p : out.V) p *= factor;
  return out;
}

PolygonMesh scaled(const PolygonMesh& mesh, double factor) {
  detail::require_positive_length("scaled", "factor", factor);
  PolygonMesh out = mesh;
  for (auto& p : out.V) p *= factor;
  return out;
}

IndexedMesh translated(const IndexedMesh& mesh, const Eigen::Vector3d& offset) {
  require_finite_offset(offset);
  IndexedMesh out = mesh;
  for (auto& p : out.V) p += offset;
  return out;
}

PolygonMesh translated(const PolygonMesh& mesh, const Eigen::Vector3d& offset) {
  require_finite_offset(offset);
  PolygonMesh out = mesh;
  for (auto& p : out.V) p += offset;
  return out;
}

IndexedMesh merged(const IndexedMesh& a, const IndexedMesh& b) {
  IndexedMesh out = a;
  const auto shift = static_cast<Index>(a.V.size());
  out.V.insert(out.V.end(), b.V.begin(), b.V.end());
  for (const auto& t : b.F) out.F.push_back({t[0] + shift, t[1] + shift, t[2] + shift});
  return out;
}

PolygonMesh merged(const PolygonMesh& a, const PolygonMesh& b) {
  PolygonMesh out = a;
  const auto shift = static_cast<Index>(a.V.size());
  out.V.insert(out.V.end(), b.V.begin(), b.V.end());
  for (const auto& f : b.faces) {
    sim::PolygonFace g;
    g.outer = shifted(f.outer, shift);
    for (const auto& h : f.holes) g.holes.push_back(shifted(h, shift));
    out.faces.push_back(std::move(g));
  }
  return out;
}

IndexedMesh triangulated_with_holes(const PolygonMesh& mesh) {
  // Relative planarity tolerance: round-off of coordinates that were computed, not a
  // modelling tolerance (faces of the generators here are exactly planar).
  constexpr double kPlanarity = 1e-9;
  IndexedMesh out;
  out.V = mesh.V;
  for (std::size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    const auto& face = mesh.faces[fi];
    const std::string context = fmt::format("triangulated_with_holes: face {}", fi);
    if (face.outer.size() < 3) throw InputError(fmt::format("{} has fewer than 3 vertices", context));
    for (Index v : face.outer)
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.V.size())
        throw InputError(fmt::format("{} uses vertex {} of {}", context, v, mesh.V.size()));
    if (face.outer.size() == 3 && face.holes.empty()) {
      out.F.push_back({face.outer[0], face.outer[1], face.outer[2]});
      continue;
    }
    // Newell normal of the outer loop: its direction is the side the loop is CCW around.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    double extent = 0.0;
    const auto& o = face.outer;
    for (std::size_t k = 0; k < o.size(); ++k) {
      const auto& p = mesh.V[static_cast<std::size_t>(o[k])];
      const auto& q = mesh.V[static_cast<std::size_t>(o[(k + 1) % o.size()])];
      normal += p.cross(q);
      extent = std::max(extent, (q - p).norm());
    }
    if (!(normal.norm() > 0.0) || !(extent > 0.0))
      throw InputError(fmt::format("{} is degenerate (zero area)", context));
    normal.normalize();
    // Frame (u, v) with u x v = normal, so CCW around the normal stays CCW in 2-D.
    const Eigen::Vector3d u = normal.unitOrthogonal();
    const Eigen::Vector3d v = normal.cross(u);
    const Eigen::Vector3d origin = mesh.V[static_cast<std::size_t>(o[0])];
    std::vector<Eigen::Vector2d> pts;
    std::vector<Index> global;
    std::vector<std::vector<int>> loops;
    auto add_loop = [&](const std::vector<Index>& loop) {
      std::vector<int> local;
      for (Index g : loop) {
        if (g < 0 || static_cast<std::size_t>(g) >= mesh.V.size())
          throw InputError(fmt::format("{} uses vertex {} of {}", context, g, mesh.V.size()));
        const Eigen::Vector3d d = mesh.V[static_cast<std::size_t>(g)] - origin;
        if (std::abs(d.dot(normal)) > kPlanarity * extent)
          throw InputError(fmt::format("{} is not planar: vertex v{} is {} off its plane", context, g, d.dot(normal)));
        local.push_back(static_cast<int>(pts.size()));
        pts.emplace_back(d.dot(u), d.dot(v));
        global.push_back(g);
      }
      loops.push_back(std::move(local));
    };
    add_loop(face.outer);
    for (const auto& h : face.holes) add_loop(h);
    for (const auto& t : detail::constrained_triangles(pts, loops, context))
      out.F.push_back({global[static_cast<std::size_t>(t[0])], global[static_cast<std::size_t>(t[1])],
                       global[static_cast<std::size_t>(t[2])]});
  }
  return out;
}

}  // namespace meltlab::datasets
