#include <meltlab/sim/mesh_order.h>

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace meltlab::sim {

namespace {
// Spreads the low 21 bits of x so that there are two zero bits between each.
std::uint64_t spread_bits(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}
}  // namespace

Reordered reorder_for_locality(const IndexedMesh& in) {
  const std::size_t nv = in.V.size();
  Vec3<double> lo = Vec3<double>::Constant(0), hi = Vec3<double>::Constant(0);
  if (nv > 0) {
    lo = hi = in.V[0];
    for (const auto& p : in.V) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const Vec3<double> extent = (hi - lo).cwiseMax(Vec3<double>::Constant(1e-300));
  constexpr double kCells = (1 << 21) - 1;
  std::vector<std::uint64_t> code(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const Vec3<double> u = (in.V[v] - lo).cwiseQuotient(extent) * kCells;
    code[v] = spread_bits(static_cast<std::uint64_t>(u.x())) | spread_bits(static_cast<std::uint64_t>(u.y())) << 1 |
              spread_bits(static_cast<std::uint64_t>(u.z())) << 2;
  }
  std::vector<Index> order(nv);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](Index a, Index b) {
    return code[static_cast<std::size_t>(a)] < code[static_cast<std::size_t>(b)];
  });
  Reordered out;
  out.new_from_old_vertex.resize(nv);
  out.mesh.V.resize(nv);
  for (std::size_t k = 0; k < nv; ++k) {
    out.new_from_old_vertex[static_cast<std::size_t>(order[k])] = static_cast<Index>(k);
    out.mesh.V[k] = in.V[static_cast<std::size_t>(order[k])];
  }
  std::vector<Triangle> tris(in.F.size());
  for (std::size_t t = 0; t < in.F.size(); ++t) {
    Triangle r;
    for (int k = 0; k < 3; ++k)
      r[static_cast<std::size_t>(k)] =
          out.new_from_old_vertex[static_cast<std::size_t>(in.F[t][static_cast<std::size_t>(k)])];
    tris[t] = rotate_min_first(r);
  }
  out.old_from_new_triangle.resize(in.F.size());
  std::iota(out.old_from_new_triangle.begin(), out.old_from_new_triangle.end(), 0);
  std::stable_sort(out.old_from_new_triangle.begin(), out.old_from_new_triangle.end(), [&](Index a, Index b) {
    return tris[static_cast<std::size_t>(a)] < tris[static_cast<std::size_t>(b)];
  });
  out.mesh.F.resize(in.F.size());
  for (std::size_t t = 0; t < in.F.size(); ++t)
    out.mesh.F[t] = tris[static_cast<std::size_t>(out.old_from_new_triangle[t])];
  return out;
}

}  // namespace meltlab::sim
