#pragma once
// A regular grid of cell-centred values: the one dense 3-D grid of meltlab. The state of the
// physically based reference melt (sim/physics), the medium the photo-like renderer traces
// rays through, and the scalar volumes of the volume renderers are all Grid3s.
//
// Frame and units: world frame (metres for the melt; scene units for the volume renderers), z up.
// Cell (i, j, k) is the cube origin_m + [i, i+1] x [j, j+1] x [k, k+1] * h_m;
// its value is the cell average (sampled at the centre origin_m + (i+½, j+½, k+½) h_m).
// Storage is x fastest: index = i + nx * (j + ny * k).

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace meltlab {

template <class T>
struct Grid3 {
  int nx = 0, ny = 0, nz = 0;
  double h_m = 0;                                      ///< cell edge length, metres
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();  ///< corner of cell (0, 0, 0), metres
  std::vector<T> value;

  Grid3() = default;
  Grid3(int nx_, int ny_, int nz_, double h, const Eigen::Vector3d& origin, T fill = T{})
      : nx(nx_),
        ny(ny_),
        nz(nz_),
        h_m(h),
        origin_m(origin),
        value(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) * static_cast<std::size_t>(nz_), fill) {}

  std::size_t size() const { return value.size(); }
  bool empty() const { return value.empty(); }
  std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(nx) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(ny) * static_cast<std::size_t>(k));
  }
  T& at(int i, int j, int k) { return value[index(i, j, k)]; }
  const T& at(int i, int j, int k) const { return value[index(i, j, k)]; }
  bool inside(int i, int j, int k) const { return i >= 0 && j >= 0 && k >= 0 && i < nx && j < ny && k < nz; }
  Eigen::Vector3d centre_m(int i, int j, int k) const {
    return origin_m + h_m * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
  }
  /// World-space box covered by the grid.
  Eigen::Vector3d min_m() const { return origin_m; }
  Eigen::Vector3d max_m() const { return origin_m + h_m * Eigen::Vector3d(nx, ny, nz); }

  /// Trilinear interpolation between cell centres at a world point; `outside` beyond the
  /// outermost centres' half-cell border (values are clamped to the border cells inside it).
  double sample(const Eigen::Vector3d& p_m, double outside = 0.0) const {
    const Eigen::Vector3d g = (p_m - origin_m) / h_m - Eigen::Vector3d::Constant(0.5);
    if (g.x() < -0.5 || g.y() < -0.5 || g.z() < -0.5 || g.x() > nx - 0.5 || g.y() > ny - 0.5 || g.z() > nz - 0.5)
      return outside;
    const double fx = std::floor(g.x()), fy = std::floor(g.y()), fz = std::floor(g.z());
    const double tx = g.x() - fx, ty = g.y() - fy, tz = g.z() - fz;
    const int i0 = static_cast<int>(fx), j0 = static_cast<int>(fy), k0 = static_cast<int>(fz);
    auto v = [&](int i, int j, int k) {
      return static_cast<double>(at(std::clamp(i, 0, nx - 1), std::clamp(j, 0, ny - 1), std::clamp(k, 0, nz - 1)));
    };
    const double c00 = v(i0, j0, k0) * (1 - tx) + v(i0 + 1, j0, k0) * tx;
    const double c10 = v(i0, j0 + 1, k0) * (1 - tx) + v(i0 + 1, j0 + 1, k0) * tx;
    const double c01 = v(i0, j0, k0 + 1) * (1 - tx) + v(i0 + 1, j0, k0 + 1) * tx;
    const double c11 = v(i0, j0 + 1, k0 + 1) * (1 - tx) + v(i0 + 1, j0 + 1, k0 + 1) * tx;
    return (c00 * (1 - ty) + c10 * ty) * (1 - tz) + (c01 * (1 - ty) + c11 * ty) * tz;
  }
};

}  // namespace meltlab
