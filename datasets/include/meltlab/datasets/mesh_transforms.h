#pragma once
// Small whole-mesh operations used to place and combine procedural shapes. Orientation is
// preserved by all of them (a uniform positive scale, a translation and a disjoint union
// keep outward faces outward).

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/polygon_mesh.h>

#include <Eigen/Core>

namespace meltlab::datasets {

/// Every position multiplied by `factor` (> 0 and finite, else InputError: a negative
/// factor would turn the solid inside out).
sim::IndexedMesh scaled(const sim::IndexedMesh& mesh, double factor);
sim::PolygonMesh scaled(const sim::PolygonMesh& mesh, double factor);

/// Every position moved by `offset` (mesh units; must be finite).
sim::IndexedMesh translated(const sim::IndexedMesh& mesh, const Eigen::Vector3d& offset);
sim::PolygonMesh translated(const sim::PolygonMesh& mesh, const Eigen::Vector3d& offset);

/// Disjoint union: the vertices and faces of `b` appended after those of `a`, `b`'s
/// indices shifted by a.V.size(). Nothing is welded, so S adds up.
sim::IndexedMesh merged(const sim::IndexedMesh& a, const sim::IndexedMesh& b);
sim::PolygonMesh merged(const sim::PolygonMesh& a, const sim::PolygonMesh& b);

/// Triangulation of a polygon mesh whose faces may have holes (unlike sim::triangulate,
/// which fans and refuses holes). Each face must be planar within 1e-9 of its size; it is
/// projected onto its own plane and triangulated with a constrained Delaunay triangulation
/// of its outer and hole loops (no vertices added). Orientation follows the outer loop.
/// A face with n loop vertices and h holes gives n + 2h - 2 triangles, so V, S and G are
/// kept and H becomes 0. Throws InputError naming the face if a face is not planar, has
/// crossing loops, or is degenerate.
sim::IndexedMesh triangulated_with_holes(const sim::PolygonMesh& mesh);

}  // namespace meltlab::datasets
