// Marching tetrahedra on the Kuhn decomposition (see isosurface.h).
#include <meltlab/sim/physics/isosurface.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>

namespace meltlab::sim::physics {

IndexedMesh isosurface(const Grid3<float>& fraction, double level) {
  IndexedMesh out;
  const int nx = fraction.nx, ny = fraction.ny, nz = fraction.nz;
  if (fraction.empty()) return out;
  // padded lattice of cell centres: node (I, J, K), I in [-1, nx], value 0 outside the grid
  const std::int64_t px = nx + 2, py = ny + 2;
  auto node_id = [&](int I, int J, int K) -> std::int64_t {
    return (I + 1) + px * ((J + 1) + py * static_cast<std::int64_t>(K + 1));
  };
  auto value = [&](int I, int J, int K) -> double {
    return fraction.inside(I, J, K) ? static_cast<double>(fraction.at(I, J, K)) : 0.0;
  };
  auto position = [&](int I, int J, int K) -> Eigen::Vector3d {
    return fraction.origin_m + fraction.h_m * Eigen::Vector3d(I + 0.5, J + 0.5, K + 0.5);
  };
  const std::int64_t n_nodes = px * py * (nz + 2);
  std::unordered_map<std::int64_t, Index> edge_vertex;

  // Kuhn tetrahedra: corners 000, e_p0, e_p0 + e_p1, 111 for the 6 axis permutations
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  constexpr double kClamp = 1e-4;

  struct Corner {
    int I, J, K;
    double v;
    bool in;
  };
  auto vertex_on = [&](const Corner& a, const Corner& b) -> Index {
    std::int64_t ia = node_id(a.I, a.J, a.K), ib = node_id(b.I, b.J, b.K);
    const bool swapped = ia > ib;
    if (swapped) std::swap(ia, ib);
    const std::int64_t key = ia * n_nodes + ib;
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    const Corner& lo = swapped ? b : a;  // lo has the smaller node id: the interpolation is direction independent
    const Corner& hi = swapped ? a : b;
    double t = (level - lo.v) / (hi.v - lo.v);
    t = std::clamp(t, kClamp, 1.0 - kClamp);
    const Eigen::Vector3d p = (1.0 - t) * position(lo.I, lo.J, lo.K) + t * position(hi.I, hi.J, hi.K);
    const auto id = static_cast<Index>(out.V.size());
    out.V.push_back(p);
    edge_vertex.emplace(key, id);
    return id;
  };
  // emit (a, b, c) oriented so its normal points away from the tet's inside corners; decided
  // on the edge midpoints (same combinatorics, well conditioned)
  auto emit = [&](const std::array<std::pair<const Corner*, const Corner*>, 3>& e, const Eigen::Vector3d& inside_c) {
    Eigen::Vector3d m[3];
    for (int q = 0; q < 3; ++q)
      m[q] = 0.5 * (position(e[q].first->I, e[q].first->J, e[q].first->K) +
                    position(e[q].second->I, e[q].second->J, e[q].second->K));
    const Eigen::Vector3d nrm = (m[1] - m[0]).cross(m[2] - m[0]);
    const bool flip = nrm.dot(inside_c - m[0]) > 0;
    Index v[3];
    for (int q = 0; q < 3; ++q) v[q] = vertex_on(*e[q].first, *e[q].second);
    if (flip) std::swap(v[1], v[2]);
    out.F.push_back({v[0], v[1], v[2]});
  };

  for (int K = -1; K < nz; ++K)
    for (int J = -1; J < ny; ++J)
      for (int I = -1; I < nx; ++I) {
        double cv[8];
        int n_in = 0;
        for (int c = 0; c < 8; ++c) {
          cv[c] = value(I + (c & 1), J + ((c >> 1) & 1), K + ((c >> 2) & 1));
          n_in += cv[c] > level;
        }
        if (n_in == 0 || n_in == 8) continue;
        for (const auto& perm : kPerm) {
          Corner t[4];
          int off[3] = {0, 0, 0};
          for (int q = 0; q < 4; ++q) {
            if (q > 0 && q < 3) off[perm[q - 1]] = 1;
            if (q == 3) off[0] = off[1] = off[2] = 1;
            const int ci = off[0] | (off[1] << 1) | (off[2] << 2);
            t[q] = Corner{I + off[0], J + off[1], K + off[2], cv[ci], cv[ci] > level};
          }
          int ins[4], outs[4], ni = 0, no = 0;
          Eigen::Vector3d ic = Eigen::Vector3d::Zero();
          for (int q = 0; q < 4; ++q) {
            if (t[q].in) {
              ins[ni++] = q;
              ic += position(t[q].I, t[q].J, t[q].K);
            } else {
              outs[no++] = q;
            }
          }
          if (ni == 0 || ni == 4) continue;
          ic /= ni;
          if (ni == 1) {
            const Corner* a = &t[ins[0]];
            emit({{{a, &t[outs[0]]}, {a, &t[outs[1]]}, {a, &t[outs[2]]}}}, ic);
          } else if (ni == 3) {
            const Corner* a = &t[outs[0]];
            emit({{{&t[ins[0]], a}, {&t[ins[1]], a}, {&t[ins[2]], a}}}, ic);
          } else {
            const Corner *a = &t[ins[0]], *b = &t[ins[1]], *c = &t[outs[0]], *d = &t[outs[1]];
            // quad ac, ad, bd, bc (cyclic); two triangles
            emit({{{a, c}, {a, d}, {b, d}}}, ic);
            emit({{{a, c}, {b, d}, {b, c}}}, ic);
          }
        }
      }
  return out;
}

}  // namespace meltlab::sim::physics
