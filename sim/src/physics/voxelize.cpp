// Mesh -> volume fraction by z-ray parity with sub-sampling (see voxelize.h).
#include <meltlab/sim/physics/voxelize.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace meltlab::sim::physics {

void voxelize_into(const IndexedMesh& mesh, Grid3<float>& grid, int subsamples) {
  if (grid.empty() || !(grid.h_m > 0)) throw std::invalid_argument("voxelize_into: empty grid");
  const int S = std::max(subsamples, 1);
  const int nx = grid.nx, ny = grid.ny, nz = grid.nz;
  const double h = grid.h_m;
  const Eigen::Vector3d o = grid.origin_m;
  std::fill(grid.value.begin(), grid.value.end(), 0.0f);

  // bin triangles to the columns their xy bounding box touches
  std::vector<std::vector<int>> bins(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (std::size_t t = 0; t < mesh.F.size(); ++t) {
    const auto& f = mesh.F[t];
    const auto& a = mesh.V[static_cast<std::size_t>(f[0])];
    const auto& b = mesh.V[static_cast<std::size_t>(f[1])];
    const auto& c = mesh.V[static_cast<std::size_t>(f[2])];
    const double x0 = std::min({a.x(), b.x(), c.x()}), x1 = std::max({a.x(), b.x(), c.x()});
    const double y0 = std::min({a.y(), b.y(), c.y()}), y1 = std::max({a.y(), b.y(), c.y()});
    const int i0 = std::max(0, static_cast<int>(std::floor((x0 - o.x()) / h)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::floor((x1 - o.x()) / h)));
    const int j0 = std::max(0, static_cast<int>(std::floor((y0 - o.y()) / h)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((y1 - o.y()) / h)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i)
        bins[static_cast<std::size_t>(i) + static_cast<std::size_t>(nx) * static_cast<std::size_t>(j)].push_back(
            static_cast<int>(t));
  }
  // fixed irrational jitter so sub-sample rays never pass exactly through edges or vertices
  const double jx = 0.6180339887498949e-6 * h, jy = 0.4142135623730950e-6 * h;
  const double w = 1.0 / (static_cast<double>(S) * static_cast<double>(S));

  tbb::parallel_for(tbb::blocked_range<int>(0, ny), [&](const tbb::blocked_range<int>& r) {
    std::vector<double> zs, col(static_cast<std::size_t>(nz));
    for (int j = r.begin(); j != r.end(); ++j)
      for (int i = 0; i < nx; ++i) {
        const auto& bin =
            bins[static_cast<std::size_t>(i) + static_cast<std::size_t>(nx) * static_cast<std::size_t>(j)];
        if (bin.empty()) continue;
        std::fill(col.begin(), col.end(), 0.0);
        for (int sa = 0; sa < S; ++sa)
          for (int sb = 0; sb < S; ++sb) {
            const double px = o.x() + (i + (sa + 0.5) / S) * h + jx;
            const double py = o.y() + (j + (sb + 0.5) / S) * h + jy;
            zs.clear();
            for (int t : bin) {
              const auto& f = mesh.F[static_cast<std::size_t>(t)];
              const auto& a = mesh.V[static_cast<std::size_t>(f[0])];
              const auto& b = mesh.V[static_cast<std::size_t>(f[1])];
              const auto& c = mesh.V[static_cast<std::size_t>(f[2])];
              const double w0 = (b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px);
              const double w1 = (c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px);
              const double w2 = (a.x() - px) * (b.y() - py) - (a.y() - py) * (b.x() - px);
              const bool pos = w0 >= 0 && w1 >= 0 && w2 >= 0, neg = w0 <= 0 && w1 <= 0 && w2 <= 0;
              const double sum = w0 + w1 + w2;
              if (!(pos || neg) || sum == 0) continue;
              zs.push_back((w0 * a.z() + w1 * b.z() + w2 * c.z()) / sum);
            }
            std::sort(zs.begin(), zs.end());
            for (std::size_t q = 0; q + 1 < zs.size(); q += 2) {
              const double z0 = (zs[q] - o.z()) / h, z1 = (zs[q + 1] - o.z()) / h;  // in cell units
              const int k0 = std::max(0, static_cast<int>(std::floor(z0)));
              const int k1 = std::min(nz - 1, static_cast<int>(std::floor(z1)));
              for (int k = k0; k <= k1; ++k) {
                const double len = std::min(z1, k + 1.0) - std::max(z0, static_cast<double>(k));
                if (len > 0) col[static_cast<std::size_t>(k)] += len * w;
              }
            }
          }
        for (int k = 0; k < nz; ++k)
          grid.at(i, j, k) = static_cast<float>(std::min(col[static_cast<std::size_t>(k)], 1.0));
      }
  });
}

Grid3<float> voxelize_fraction(const IndexedMesh& mesh, const VoxelizeOptions& options) {
  if (mesh.V.empty() || mesh.F.empty()) throw std::invalid_argument("voxelize_fraction: empty mesh");
  if (!(options.h_m > 0)) throw std::invalid_argument("voxelize_fraction: h must be > 0");
  Eigen::Vector3d lo = mesh.V[0], hi = mesh.V[0];
  for (const auto& v : mesh.V) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double h = options.h_m;
  const int m = std::max(options.margin_cells, 0);
  Eigen::Vector3d origin;
  int n[3];
  for (int a = 0; a < 3; ++a) {
    const int inner = std::max(1, static_cast<int>(std::ceil((hi[a] - lo[a]) / h - 1e-9)));
    if (a == 2 && options.floor_at_mesh_bottom) {
      n[a] = inner + m;
      origin[a] = lo[a];
    } else {
      n[a] = inner + 2 * m;
      origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * n[a] * h;
    }
  }
  Grid3<float> g(n[0], n[1], n[2], h, origin, 0.0f);
  voxelize_into(mesh, g, options.subsamples);
  return g;
}

Grid3<std::uint8_t> voxelize_occupancy(const IndexedMesh& mesh, const VoxelizeOptions& options) {
  const auto f = voxelize_fraction(mesh, options);
  Grid3<std::uint8_t> o(f.nx, f.ny, f.nz, f.h_m, f.origin_m, 0);
  for (std::size_t c = 0; c < f.size(); ++c) o.value[c] = f.value[c] >= 0.5f ? 1 : 0;
  return o;
}

double grid_volume(const Grid3<float>& fraction) {
  double s = 0;
  for (float v : fraction.value) s += static_cast<double>(v);
  return s * fraction.h_m * fraction.h_m * fraction.h_m;
}

}  // namespace meltlab::sim::physics
