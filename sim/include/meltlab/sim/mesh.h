#pragma once
// Indexed triangle mesh in structure-of-arrays form with existence flags (monograph §2.2,
// §3.5). Every per-element vector quantity (P, N, M, Nf) is itself stored as three arrays of
// its components (Vec3Columns): the melt kernels load eight consecutive x (or y, z) with one
// SIMD instruction; other code reads element i as a Vec3 with `position[i]` and writes it
// with `position.set(i, p)`. Arrays keep their length while a melt runs: deleting an element clears its flag
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
#include <cstddef>
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

/// Three-component vectors stored as three arrays (structure of arrays): x[i], y[i], z[i]
/// are the components of element i. The melt kernels read and write the columns with SIMD
/// loads and stores; everyone else reads an element through operator[], which returns a
/// copy as a Vec3, and writes it with set().
template <class Real>
class Vec3Columns {
 public:
  /// Reads elements as Vec3 values (range-for over a column set).
  class const_iterator {
   public:
    using value_type = Vec3<Real>;
    using difference_type = std::ptrdiff_t;
    const_iterator() = default;
    const_iterator(const Vec3Columns* c, std::size_t i) : c_(c), i_(i) {}
    const Vec3<Real> operator*() const { return (*c_)[i_]; }
    const_iterator& operator++() {
      ++i_;
      return *this;
    }
    const_iterator operator++(int) {
      const_iterator old = *this;
      ++i_;
      return old;
    }
    bool operator==(const const_iterator& o) const { return i_ == o.i_; }

   private:
    const Vec3Columns* c_ = nullptr;
    std::size_t i_ = 0;
  };

  Vec3Columns() = default;
  /// `n` zero vectors.
  explicit Vec3Columns(std::size_t n) : x_(n, Real(0)), y_(n, Real(0)), z_(n, Real(0)) {}

  std::size_t size() const { return x_.size(); }
  bool empty() const { return x_.empty(); }
  /// Element i as a vector (a copy; const, so that `position[i].x() = 1` does not compile
  /// and silently change nothing: write with set(i, v) or through the columns).
  const Vec3<Real> operator[](std::size_t i) const { return Vec3<Real>(x_[i], y_[i], z_[i]); }
  void set(std::size_t i, const Vec3<Real>& v) {
    x_[i] = v.x();
    y_[i] = v.y();
    z_[i] = v.z();
  }
  void push_back(const Vec3<Real>& v) {
    x_.push_back(v.x());
    y_.push_back(v.y());
    z_.push_back(v.z());
  }
  /// New elements are zero.
  void resize(std::size_t n) {
    x_.resize(n, Real(0));
    y_.resize(n, Real(0));
    z_.resize(n, Real(0));
  }
  void reserve(std::size_t n) {
    x_.reserve(n);
    y_.reserve(n);
    z_.reserve(n);
  }
  void shrink_to_fit() {
    x_.shrink_to_fit();
    y_.shrink_to_fit();
    z_.shrink_to_fit();
  }
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, size()}; }

  /// The columns (for kernels): component `axis` (0 = x, 1 = y, 2 = z) of every element.
  std::vector<Real>& column(int axis) { return axis == 0 ? x_ : (axis == 1 ? y_ : z_); }
  const std::vector<Real>& column(int axis) const { return axis == 0 ? x_ : (axis == 1 ? y_ : z_); }
  std::vector<Real>& x() { return x_; }
  std::vector<Real>& y() { return y_; }
  std::vector<Real>& z() { return z_; }
  const std::vector<Real>& x() const { return x_; }
  const std::vector<Real>& y() const { return y_; }
  const std::vector<Real>& z() const { return z_; }

  /// Packed copy (x, y, z of each element together), e.g. for a library that wants triples.
  std::vector<Vec3<Real>> to_vectors() const {
    std::vector<Vec3<Real>> out(size());
    for (std::size_t i = 0; i < size(); ++i) out[i] = (*this)[i];
    return out;
  }
  template <class Other>
  Vec3Columns<Other> cast() const {
    Vec3Columns<Other> out(size());
    for (int a = 0; a < 3; ++a)
      for (std::size_t i = 0; i < size(); ++i) out.column(a)[i] = static_cast<Other>(column(a)[i]);
    return out;
  }
  bool operator==(const Vec3Columns& o) const = default;

 private:
  std::vector<Real> x_, y_, z_;
};

/// The number of flags equal to 1 among flags[0, n): std::count(flags, flags + n, 1), vectorised
/// (TriMesh's live counts, which the melt cycle takes every cycle).
std::size_t count_live_flags(const std::uint8_t* flags, std::size_t n);

template <class Real>
struct TriMesh {
  using Scalar = Real;

  // ---- vertex arrays (monograph Tab. of §3.5: e, P, N, M, t, i) ----
  std::vector<std::uint8_t> vertex_alive;  ///< e: 1 = live, 0 = deleted
  Vec3Columns<Real> position;              ///< P: object frame, mesh units
  // N, M and Nf are written by deform(), and by MeltSimulator only with set_record_vectors(true).
  Vec3Columns<Real> normal;           ///< N: unit outward vertex normal (Eq. 2.10); 0 if undefined
  Vec3Columns<Real> displacement;     ///< M: the move applied to P in the last cycle, mesh units
  std::vector<Index> triangle_count;  ///< t: live triangles on the vertex (after the last cycle)
  std::vector<Index> reindex;         ///< i: merge target of the last collapse pass (i == self if none)

  // ---- triangle arrays (e, a b c, Nf) ----
  std::vector<std::uint8_t> triangle_alive;  ///< e
  std::vector<Triangle> triangle;            ///< (a, b, c), CCW from outside, a = min index
  Vec3Columns<Real> face_normal;             ///< Nf: unit outward face normal (Eq. 2.9); 0 if degenerate

  std::size_t vertex_slots() const { return position.size(); }
  std::size_t triangle_slots() const { return triangle.size(); }
  /// The flags equal to 1 (std::count's answer, faster).
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
  out.position = position.template cast<Other>();
  out.normal = normal.template cast<Other>();
  out.displacement = displacement.template cast<Other>();
  out.face_normal = face_normal.template cast<Other>();
  return out;
}

}  // namespace meltlab::sim
