// The melt cycle on OpenMesh (see openmesh_peer.h for the model and the differences from
// sim::MeltSimulator).
//
// Choices, each the faster of the idiomatic options, measured on benchmark object C
// (32000 triangles, kE = 0.05 L0, kN = kE/100, kr = 0.5 L0, first 100 cycles, float,
// release, one pinned core, ms per cycle):
//   * Vertex normals: OpenMesh's update_vertex_normals() computes exactly Eq. 2.10 (its
//     calc_vertex_normal uses calc_vertex_normal_fast: the sum of the stored unit face
//     normals over a vertex-face circulation, then normalised; not the sector-weighted
//     "correct" or the Loop variant). Calling it costs a second circulation per vertex, so
//     N is summed in the same outgoing-half-edge circulation that sums M_E
//     (deform 1.00 ms fused vs 1.33 ms with update_vertex_normals()). Same numbers up to
//     summation order: face_handle(h) over the outgoing half-edges visits every incident
//     face exactly once on a closed mesh.
//   * Face normals: update_face_normals() (PolyMeshT's Newell loop) and a loop calling
//     TriMeshT::calc_face_normal per face cost the same; the library call is kept.
//   * Garbage collection: every cycle costs 0.55 ms per cycle in the collapse pass (it
//     re-allocates its handle maps and swaps properties), lazily 0.28 ms; skipping the dead
//     slots costs the other passes nothing measurable. Dead slots are compacted once they
//     are half of the vertex slots, which bounds the sweep overhead at 2x over a long melt.

#include <meltlab/core/time.h>
#include "openmesh_peer.h"

#include <meltlab/core/error.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <fmt/format.h>

#include <array>
#include <chrono>

namespace meltlab::bench {

namespace {

// Points and normals in Real; status flags on vertices, edges and faces (collapse and
// garbage collection need them); stored face normals; the default previous-half-edge link.
template <class Real>
struct PeerTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::VectorT<Real, 3>;
  using Normal = OpenMesh::VectorT<Real, 3>;
  VertexAttributes(OpenMesh::Attributes::Status);
  HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge);
  EdgeAttributes(OpenMesh::Attributes::Status);
  FaceAttributes(OpenMesh::Attributes::Status | OpenMesh::Attributes::Normal);
};

// Dead vertex slots are compacted once they reach this share of all vertex slots.
constexpr std::int64_t kGarbagePercent = 50;

}  // namespace

template <class Real>
struct OpenMeshMeltPeerT<Real>::Impl {
  using Mesh = OpenMesh::TriMesh_ArrayKernelT<PeerTraits<Real>>;
  using Point = typename Mesh::Point;
  using Normal = typename Mesh::Normal;

  Mesh mesh;
  sim::MeltParams params;
  OpenMesh::VPropHandleT<Point> move;  ///< Alg. 1's displacement, applied after the sweep
  OpenMesh::VPropHandleT<int> pass;    ///< the collapse pass that last touched the vertex
  std::int64_t live_vertices = 0, live_faces = 0;
  std::int64_t dead_vertices = 0;  ///< deleted but not yet garbage-collected
  int pass_counter = 0;

  void deform();
  void collapse(sim::CycleReport& report);
  void delete_tetrahedron(typename Mesh::HalfedgeHandle heh, sim::CycleReport& report);
};

template <class Real>
OpenMeshMeltPeerT<Real>::OpenMeshMeltPeerT(const sim::IndexedMesh& in, const sim::MeltParams& params)
    : impl_(std::make_unique<Impl>()) {
  params.validate();
  if (params.deform != sim::DeformMode::kCombined)
    throw InputError("deform: the OpenMesh peer implements only the combined rule (Eq. 3.6)");
  Impl& s = *impl_;
  s.params = params;
  auto& m = s.mesh;
  m.reserve(in.V.size(), in.V.size() + in.F.size(), in.F.size());
  for (const auto& p : in.V)
    m.add_vertex(typename Impl::Point(static_cast<Real>(p.x()), static_cast<Real>(p.y()), static_cast<Real>(p.z())));
  const auto nv = static_cast<sim::Index>(in.V.size());
  for (std::size_t f = 0; f < in.F.size(); ++f) {
    const sim::Triangle& t = in.F[f];
    for (sim::Index v : t)
      if (v < 0 || v >= nv) throw InputError(fmt::format("mesh: face {} uses vertex {} of {}", f, v, nv));
    const auto fh =
        m.add_face(OpenMesh::VertexHandle(t[0]), OpenMesh::VertexHandle(t[1]), OpenMesh::VertexHandle(t[2]));
    if (!fh.is_valid())
      throw InputError(fmt::format("mesh: face {} ({}, {}, {}) makes the surface non-manifold", f, t[0], t[1], t[2]));
  }
  for (auto vh : m.vertices())
    if (vh.is_boundary()) throw InputError(fmt::format("mesh: vertex {} is on a boundary or on no face", vh.idx()));
  m.add_property(s.move);
  m.add_property(s.pass);
  for (auto vh : m.vertices()) m.property(s.pass, vh) = -1;
  s.live_vertices = static_cast<std::int64_t>(m.n_vertices());
  s.live_faces = static_cast<std::int64_t>(m.n_faces());
}

template <class Real>
OpenMeshMeltPeerT<Real>::~OpenMeshMeltPeerT() = default;
template <class Real>
OpenMeshMeltPeerT<Real>::OpenMeshMeltPeerT(OpenMeshMeltPeerT&&) noexcept = default;
template <class Real>
OpenMeshMeltPeerT<Real>& OpenMeshMeltPeerT<Real>::operator=(OpenMeshMeltPeerT&&) noexcept = default;

template <class Real>
void OpenMeshMeltPeerT<Real>::Impl::deform() {
  using Scalar = Real;
  const auto kE = static_cast<Scalar>(params.kE), kN = static_cast<Scalar>(params.kN);
  const auto s = static_cast<Scalar>(params.kg);  // kg · kl with kl = 1
  const bool less_equal = params.tie == sim::TieRule::kLessEqual;
  const bool mean = params.edge_sum == sim::EdgeSumMode::kMean;
  mesh.update_face_normals();  // unit (Eq. 2.9); degenerate faces get 0
  for (auto vh : mesh.vertices()) {
    const Point p = mesh.point(vh);
    Normal N(0, 0, 0);
    Point ME(0, 0, 0);
    int count = 0;
    for (auto heh : mesh.voh_range(vh)) {
      ME += (mesh.point(mesh.to_vertex_handle(heh)) - p).normalize_cond();  // a vanished edge adds 0
      N += mesh.normal(mesh.face_handle(heh));
      ++count;
    }
    Point& M = mesh.property(move, vh);
    if (count == 0) {
      M = Point(0, 0, 0);
      continue;
    }
    N.normalize_cond();  // Eq. 2.10
    if (mean) ME /= static_cast<Scalar>(count);
    const Scalar d = OpenMesh::dot(N, ME);
    // M_N = -N, so Eq. 3.6's agreement test M_N·M_E > 0 is N·M_E < 0 (Alg. 1: <=).
    const bool combined = less_equal ? d <= Scalar(0) : d < Scalar(0);
    M = combined ? (ME * kE - N * kN) * s : N * (-kN * s);
  }
  for (auto vh : mesh.vertices()) mesh.point(vh) += mesh.property(move, vh);
}

// A closed component that has shrunk to a tetrahedron: the collapse would leave a glued
// pair (which Alg. 3 deletes), so the component goes at once.
template <class Real>
void OpenMeshMeltPeerT<Real>::Impl::delete_tetrahedron(typename Mesh::HalfedgeHandle heh, sim::CycleReport& report) {
  std::array<OpenMesh::FaceHandle, 4> faces = {mesh.face_handle(heh), mesh.opposite_face_handle(heh),
                                               mesh.opposite_face_handle(mesh.next_halfedge_handle(heh)),
                                               mesh.opposite_face_handle(mesh.prev_halfedge_handle(heh))};
  for (auto fh : faces) mesh.delete_face(fh, true);  // true: its edges and vertices go with it
  report.merged_vertices += 1;
  report.degenerate_triangles += 2;
  report.glued_triangles += 2;
  report.glued_vertices += 3;
  live_vertices -= 4;
  dead_vertices += 4;
  live_faces -= 4;
}

template <class Real>
void OpenMeshMeltPeerT<Real>::Impl::collapse(sim::CycleReport& report) {
  const auto kr2 = static_cast<Real>(params.kr * params.kr);
  const int stamp = ++pass_counter;
  std::int64_t collapses = 0;
  for (auto eh : mesh.edges()) {
    const auto h0 = mesh.halfedge_handle(eh, 0);
    const auto va = mesh.to_vertex_handle(h0), vb = mesh.from_vertex_handle(h0);
    // One collapse per vertex per pass: a survivor is stamped; the removed vertex's edges
    // now end at the survivor, so they are skipped too.
    if (mesh.property(pass, va) == stamp || mesh.property(pass, vb) == stamp) continue;
    const Point pa = mesh.point(va), pb = mesh.point(vb);
    if (!((pa - pb).sqrnorm() < kr2)) continue;
    // collapse(h) removes from_vertex(h): keep the lower index, as Alg. 2 does.
    const auto heh = va.idx() < vb.idx() ? h0 : mesh.opposite_halfedge_handle(h0);
    if (!mesh.is_collapse_ok(heh)) continue;
    const auto survivor = mesh.to_vertex_handle(heh);
    if (mesh.valence(va) == 3 && mesh.valence(vb) == 3) {
      delete_tetrahedron(heh, report);
      continue;
    }
    mesh.collapse(heh);
    mesh.point(survivor) = (pa + pb) * Real(0.5);
    mesh.property(pass, survivor) = stamp;
    ++collapses;
  }
  report.merged_vertices += collapses;
  live_vertices -= collapses;
  dead_vertices += collapses;
  live_faces -= 2 * collapses;
  const auto slots = static_cast<std::int64_t>(mesh.n_vertices());
  if (dead_vertices > 0 && dead_vertices * 100 >= kGarbagePercent * slots) {
    mesh.garbage_collection();
    dead_vertices = 0;
  }
}

template <class Real>
sim::CycleReport OpenMeshMeltPeerT<Real>::step() {
  Impl& s = *impl_;
  sim::CycleReport report;
  if (s.live_faces > 0) {
    auto t0 = std::chrono::steady_clock::now();
    s.deform();
    report.deform_ms = ms_since(t0);
    t0 = std::chrono::steady_clock::now();
    s.collapse(report);
    report.collapse_ms = ms_since(t0);
  }
  report.live_vertices = s.live_vertices;
  report.live_triangles = s.live_faces;
  ++cycle_;
  return report;
}

template <class Real>
sim::IndexedMesh OpenMeshMeltPeerT<Real>::mesh() const {
  const auto& m = impl_->mesh;
  sim::IndexedMesh out;
  std::vector<sim::Index> compact(m.n_vertices(), -1);
  out.V.reserve(static_cast<std::size_t>(impl_->live_vertices));
  out.F.reserve(static_cast<std::size_t>(impl_->live_faces));
  for (auto vh : m.vertices()) {
    compact[static_cast<std::size_t>(vh.idx())] = static_cast<sim::Index>(out.V.size());
    const auto& p = m.point(vh);
    out.V.emplace_back(static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2]));
  }
  for (auto fh : m.faces()) {
    sim::Triangle t{};
    std::size_t k = 0;
    for (auto vh : fh.vertices()) t[k++] = compact[static_cast<std::size_t>(vh.idx())];
    out.F.push_back(t);
  }
  return out;
}

template <class Real>
bool OpenMeshMeltPeerT<Real>::empty() const {
  return impl_->live_faces == 0;
}

template class OpenMeshMeltPeerT<float>;
template class OpenMeshMeltPeerT<double>;

}  // namespace meltlab::bench
