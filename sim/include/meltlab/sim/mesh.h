#pragma once
// Indexed triangle mesh in structure-of-arrays form with existence flags (monograph §2.2,
// §3.5). Arrays keep their length while a melt runs: deleting an element clears its flag
// and the slot is skipped from then on, so indices stay stable and every pass of the melt
// cycle is one sweep over an array (O(n), no compaction, no re-indexing).
//
// Frames and units: positions are in the object frame, in mesh units (whatever the input
// file used; the CGAL meshes are unitless, the procedural molds are in metres).
// Orientation: triangles are counter-clockwise seen from outside, so face normals
// (b - a) x (c - a) point out of the solid (Eq. 2.9).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace meltlab::sim {

template <class Real>
using Vec3 = Eigen::Matrix<Real, 3, 1>;

using Index = std::int32_t;
using Triangle = std::array<Index, 3>;

/// Cyclic rotation that puts the smallest index first, keeping orientation (Alg. 3 sort).
constexpr Triangle rotate_min_first(const Triangle& t) {
  if (t[1] < t[0] && t[1] < t[2]) return {t[1], t[2], t[0]};
  if (t[2] < t[0] && t[2] < t[1]) return {t[2], t[0], t[1]};
  return t;
}

/// Compact indexed form: #V×3 positions and #F×3 triangle indices, no dead slots.
struct IndexedMesh {
  std::vector<Vec3<double>> V;
  std::vector<Triangle> F;
};

template <class Real>
struct TriMesh {
  using Scalar = Real;

  // ---- vertex arrays (monograph Tab. of §3.5: e, P, N, M, t, i) ----
  std::vector<std::uint8_t> vertex_alive;  ///< e: 1 = live, 0 = deleted
  std::vector<Vec3<Real>> position;        ///< P: object frame, mesh units
  std::vector<Vec3<Real>> normal;          ///< N: unit outward vertex normal (Eq. 2.10); 0 if undefined
  std::vector<Vec3<Real>> displacement;    ///< M: the move applied to P in the last cycle, mesh units
  std::vector<Index> triangle_count;       ///< t: live triangles on the vertex (after the last cycle)
  std::vector<Index> reindex;              ///< i: merge target of the last collapse pass (i == self if none)

  // ---- triangle arrays (e, a b c, Nf) ----
  std::vector<std::uint8_t> triangle_alive;  ///< e
  std::vector<Triangle> triangle;            ///< (a, b, c), CCW from outside, a = min index
  std::vector<Vec3<Real>> face_normal;       ///< Nf: unit outward face normal (Eq. 2.9); 0 if degenerate

  std::size_t vertex_slots() const { return position.size(); }
  std::size_t triangle_slots() const { return triangle.size(); }
  std::size_t live_vertex_count() const;
  std::size_t live_triangle_count() const;

  /// Appends a live vertex; returns its index.
  Index add_vertex(const Vec3<Real>& p);
  /// Appends a live triangle (rotated so the smallest index is first); returns its index.
  Index add_triangle(Index a, Index b, Index c);
  /// Reserves slots for `nv` vertices and `nt` triangles (a split appends vertices).
  void reserve(std::size_t nv, std::size_t nt);

  /// Builds the mesh from compact arrays (positions converted to Real), rotating each
  /// triangle min-first. Does not validate; see topology.h.
  static TriMesh from_indexed(const IndexedMesh& m);
  /// Live elements only, vertices renumbered in increasing slot order.
  IndexedMesh to_indexed() const;
  /// Converts to another precision (all arrays, including dead slots).
  template <class Other>
  TriMesh<Other> cast() const;
};

extern template struct TriMesh<float>;
extern template struct TriMesh<double>;

template <class Real>
template <class Other>
TriMesh<Other> TriMesh<Real>::cast() const {
  TriMesh<Other> out;
  out.vertex_alive = vertex_alive;
  out.triangle_count = triangle_count;
  out.reindex = reindex;
  out.triangle_alive = triangle_alive;
  out.triangle = triangle;
  auto conv = [](const std::vector<Vec3<Real>>& in) {
    std::vector<Vec3<Other>> o(in.size());
    for (std::size_t k = 0; k < in.size(); ++k) o[k] = in[k].template cast<Other>();
    return o;
  };
  out.position = conv(position);
  out.normal = conv(normal);
  out.displacement = conv(displacement);
  out.face_normal = conv(face_normal);
  return out;
}

}  // namespace meltlab::sim
