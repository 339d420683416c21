#pragma once
// Mesh-quality measures of the monograph (§2.4, Eq. 2.4–2.8) and basic geometry.
//
//  * twist s (Eq. 2.4): for each corner i, alpha_i is the angle between the median from
//    v_i and the segment joining the midpoints of the two sides at v_i (the mid-line, which
//    is parallel to the opposite side); s = 90° - min_i alpha_i. An equilateral triangle
//    has s = 0°; s -> 90° for slivers. (The monograph states the range as [-90°, 90°]; with
//    this construction min_i alpha_i <= 90° always — the dot products of the three medians
//    with their mid-lines sum to zero — so s lies in [0°, 90°]. See docs in quality.cpp.)
//  * dihedral measure d (Fig. 2.15): angle between the two face normals of an edge, in
//    degrees, 0° for a flat edge.
//  * triangle quality q (Eq. 2.5): 4 sqrt(3) A / (a² + b² + c²), 1 for equilateral.
// Qs, Qq average over triangles, Qd over edges (Eq. 2.6–2.8).

#include <meltlab/sim/mesh.h>

#include <array>

namespace meltlab::sim {

double triangle_twist_deg(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c);
double triangle_quality(const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c);
/// The same with the area already known (0.5 |(b - a) × (c - a)|, as the overload above takes it).
double triangle_quality(double area, const Vec3<double>& a, const Vec3<double>& b, const Vec3<double>& c);
/// The dihedral measure d of an edge from its two faces' normals, in degrees (the angle
/// between them; 0 if either is the zero vector, i.e. a degenerate face).
double dihedral_deg(const Vec3<double>& n_a, const Vec3<double>& n_b);

struct QualityReport {
  double Qs = 0;      ///< mean twist, degrees (Eq. 2.6)
  double Qd = 0;      ///< mean dihedral measure, degrees (Eq. 2.7)
  double Qq = 0;      ///< mean triangle quality (Eq. 2.8)
  double max_d = 0;   ///< largest dihedral measure, degrees
  double min_q = 0;   ///< worst triangle quality
  double volume = 0;  ///< enclosed volume (divergence theorem), mesh units³
  double area = 0;    ///< surface area, mesh units²
  Vec3<double> bbox_min = Vec3<double>::Zero();
  Vec3<double> bbox_max = Vec3<double>::Zero();
  double mean_edge_length = 0;  ///< over undirected edges, mesh units
  std::int64_t edges = 0;       ///< ne of Eq. 2.7 (edges with two faces)
};

/// Quality and geometry of the live part of a closed triangle mesh. Edges are paired by
/// filing their uses under the smaller vertex (O(n), see mesh_stats.h, which computes this
/// with the Euler counts and reuses its buffers); an edge without a twin is skipped in Qd.
template <class Real>
QualityReport mesh_quality(const TriMesh<Real>& m);

/// Volume only (cheap, O(n)): sum over live triangles of a·(b×c)/6, accumulated in double.
template <class Real>
double mesh_volume(const TriMesh<Real>& m);

}  // namespace meltlab::sim
