// Loop subdivision through OpenMesh, then longest-edge midpoint splits to an exact budget.

#include <meltlab/datasets/refine.h>
#include <meltlab/core/error.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>
#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <vector>

namespace meltlab::datasets {
namespace {

struct DoubleTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<DoubleTraits>;

constexpr std::int64_t kMaxTriangles = 100'000'000;  // far above any benchmark; guards typos

OmMesh to_openmesh(const sim::IndexedMesh& in) {
  OmMesh m;
  m.reserve(in.V.size(), in.V.size() + in.F.size(), in.F.size());
  std::vector<OmMesh::VertexHandle> vh;
  vh.reserve(in.V.size());
  for (const auto& p : in.V) vh.push_back(m.add_vertex(OmMesh::Point(p.x(), p.y(), p.z())));
  for (std::size_t f = 0; f < in.F.size(); ++f) {
    const auto& t = in.F[f];
    const auto h = m.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
    if (!h.is_valid())
      throw InputError(
          fmt::format("refine: triangle {} ({}, {}, {}) makes the mesh non-manifold", f, t[0], t[1], t[2]));
  }
  for (const auto eh : m.edges())
    if (m.is_boundary(eh)) throw InputError("refine: the mesh is open (it has a boundary edge)");
  return m;
}

sim::IndexedMesh from_openmesh(const OmMesh& m) {
  sim::IndexedMesh out;
  out.V.reserve(m.n_vertices());
  for (const auto vh : m.vertices()) {
    const auto& p = m.point(vh);
    out.V.emplace_back(p[0], p[1], p[2]);
  }
  out.F.reserve(m.n_faces());
  for (const auto fh : m.faces()) {
    sim::Triangle t{};
    int k = 0;
    for (const auto vh : m.fv_range(fh)) t[k++] = static_cast<sim::Index>(vh.idx());
    out.F.push_back(t);
  }
  return out;
}

}  // namespace

sim::IndexedMesh refined(const sim::IndexedMesh& mesh, int loop_levels, std::int64_t target_triangles) {
  if (loop_levels < 0 || loop_levels > 6)
    throw InputError(fmt::format("refine: loop_levels must be in [0, 6], got {}", loop_levels));
  if (mesh.F.empty()) throw InputError("refine: the mesh has no triangles");
  std::int64_t subdivided = static_cast<std::int64_t>(mesh.F.size());
  for (int i = 0; i < loop_levels; ++i) subdivided *= 4;
  if (subdivided > kMaxTriangles || target_triangles > kMaxTriangles)
    throw InputError(fmt::format("refine: more than {} triangles asked for", kMaxTriangles));
  if (target_triangles != 0 && (target_triangles < subdivided || (target_triangles - subdivided) % 2 != 0))
    throw InputError(
        fmt::format("refine: target_triangles {} must be 0 or {} plus an even number", target_triangles, subdivided));

  OmMesh m = to_openmesh(mesh);
  if (loop_levels > 0) {
    OpenMesh::Subdivider::Uniform::LoopT<OmMesh, double> loop;
    loop.attach(m);
    loop(static_cast<size_t>(loop_levels));
    loop.detach();
  }
  if (target_triangles != 0) {
    // The longest edges of the subdivided mesh, longest first, ties by index (deterministic).
    const auto splits = static_cast<std::size_t>((target_triangles - subdivided) / 2);
    if (splits > m.n_edges())
      throw InputError(fmt::format("refine: {} splits asked for but the mesh has {} edges; use one more loop level",
                                   splits, m.n_edges()));
    std::vector<double> length(m.n_edges());
    for (const auto eh : m.edges()) length[eh.idx()] = m.calc_edge_sqr_length(eh);
    std::vector<int> order(m.n_edges());
    std::iota(order.begin(), order.end(), 0);
    const auto longer = [&](int a, int b) { return length[a] != length[b] ? length[a] > length[b] : a < b; };
    std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(splits), order.end(), longer);
    order.resize(splits);
    std::sort(order.begin(), order.end());
    // Splitting an edge keeps the handles of all other edges, so each chosen edge is still
    // the original segment when its turn comes.
    for (const int e : order) {
      const OmMesh::EdgeHandle eh(e);
      m.split(eh, m.calc_edge_midpoint(eh));
    }
  }
  m.garbage_collection();
  return from_openmesh(m);
}

}  // namespace meltlab::datasets
