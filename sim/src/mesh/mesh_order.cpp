#include <meltlab/sim/mesh_order.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

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

// The vertices in Morton order of their positions: order[new] = old.
std::vector<Index> morton_order(const IndexedMesh& in) {
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
  return order;
}

// Renumbers the vertices by `order` (order[new] = old), rotates each triangle min-first and
// sorts the triangles by their new corners.
Reordered renumbered(const IndexedMesh& in, const std::vector<Index>& order) {
  const std::size_t nv = in.V.size();
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

// Breadth-first over the edges of `in`, each component from its lowest index, the neighbours
// of a vertex queued in ascending index: order[new] = old.
std::vector<Index> breadth_first_order(const IndexedMesh& in) {
  const std::size_t nv = in.V.size();
  // The vertex graph in compressed rows: both directions of every triangle edge.
  std::vector<std::size_t> start(nv + 1, 0);
  for (const Triangle& f : in.F)
    for (Index v : f) start[static_cast<std::size_t>(v) + 1] += 2;
  for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  std::vector<Index> nb(start[nv]);
  std::vector<std::size_t> fill(start.begin(), start.end() - 1);
  for (const Triangle& f : in.F)
    for (std::size_t k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(f[k]);
      nb[fill[v]++] = f[(k + 1) % 3];
      nb[fill[v]++] = f[(k + 2) % 3];
    }
  for (std::size_t v = 0; v < nv; ++v)
    std::sort(nb.begin() + static_cast<std::ptrdiff_t>(start[v]),
              nb.begin() + static_cast<std::ptrdiff_t>(start[v + 1]));
  std::vector<Index> order;
  order.reserve(nv);
  std::vector<std::uint8_t> queued(nv, 0);
  for (std::size_t seed = 0; seed < nv; ++seed) {
    if (queued[seed]) continue;
    queued[seed] = 1;
    order.push_back(static_cast<Index>(seed));
    for (std::size_t head = order.size() - 1; head < order.size(); ++head) {
      const auto v = static_cast<std::size_t>(order[head]);
      for (std::size_t i = start[v]; i < start[v + 1]; ++i) {
        const auto w = static_cast<std::size_t>(nb[i]);
        if (queued[w]) continue;
        queued[w] = 1;
        order.push_back(nb[i]);
      }
    }
  }
  return order;
}

}  // namespace

Reordered reorder_for_locality(const IndexedMesh& in) { return renumbered(in, morton_order(in)); }

Reordered reorder_breadth_first(const IndexedMesh& in) {
  const Reordered by_morton = reorder_for_locality(in);
  Reordered out = renumbered(by_morton.mesh, breadth_first_order(by_morton.mesh));
  // Compose the two renumberings so that both maps refer to the input.
  std::vector<Index> new_from_old(in.V.size());
  for (std::size_t v = 0; v < in.V.size(); ++v)
    new_from_old[v] = out.new_from_old_vertex[static_cast<std::size_t>(by_morton.new_from_old_vertex[v])];
  out.new_from_old_vertex = std::move(new_from_old);
  for (Index& t : out.old_from_new_triangle) t = by_morton.old_from_new_triangle[static_cast<std::size_t>(t)];
  return out;
}

}  // namespace meltlab::sim
