#include <meltlab/core/error.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/experiments/physics_body.h>
#include <meltlab/sim/physics/voxelize.h>

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <vector>

namespace meltlab::experiments {

namespace {

double signed_volume(const sim::IndexedMesh& m) {
  double v = 0;
  for (const auto& t : m.F) v += m.V[t[0]].dot(m.V[t[1]].cross(m.V[t[2]])) / 6.0;
  return v;
}

}  // namespace

PhysicsBody make_physics_body(sim::IndexedMesh mesh, double mass_g, double voxel_mm,
                              const sim::physics::IceMeltParams& physics, const std::string& source) {
  // The steps (and their order of operations) of manufacture_sequence.
  PhysicsBody b;
  const double volume0 = signed_volume(mesh);
  if (!(volume0 > 0)) throw InputError(fmt::format("{}: the mesh encloses no volume (inside out?)", source));
  const double target_volume = mass_g / 1000.0 / physics.density_kg_m3;
  b.scale = std::cbrt(target_volume / volume0);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (auto& v : mesh.V) {
    v *= b.scale;
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  b.shift = Eigen::Vector3d(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z());
  for (auto& v : mesh.V) v += b.shift;
  sim::physics::VoxelizeOptions vo;
  vo.h_m = voxel_mm / 1000.0;
  vo.margin_cells = 3;
  vo.floor_at_mesh_bottom = true;
  b.fraction = sim::physics::voxelize_fraction(mesh, vo);
  b.mesh = std::move(mesh);
  return b;
}

sim::IndexedMesh shape_mesh(const std::string& shape) {
  const auto colon = shape.find(':');
  const std::string kind = shape.substr(0, colon);
  std::vector<double> mm;
  if (colon != std::string::npos) {
    std::string rest = shape.substr(colon + 1);
    std::size_t start = 0;
    while (start <= rest.size()) {
      const std::size_t end = rest.find_first_of("x,", start);
      const std::string item = rest.substr(start, end == std::string::npos ? std::string::npos : end - start);
      double v = 0;
      const auto [ptr, err] = std::from_chars(item.data(), item.data() + item.size(), v);
      if (item.empty() || err != std::errc() || ptr != item.data() + item.size() || !std::isfinite(v) || !(v > 0))
        throw InputError(fmt::format("--shape: '{}' in '{}' is not a size in mm > 0", item, shape));
      mm.push_back(v);
      if (end == std::string::npos) break;
      start = end + 1;
    }
  }
  auto need = [&](std::size_t n, const char* form) {
    if (colon == std::string::npos || mm.size() != n)
      throw InputError(fmt::format("--shape: '{}' must be {} (millimetres)", shape, form));
  };
  if (kind == "box") {
    need(3, "box:WxDxH");
    sim::IndexedMesh m = datasets::subdivided_cube(4, 1.0);
    for (auto& v : m.V) v = Eigen::Vector3d(v.x() * mm[0], v.y() * mm[1], v.z() * mm[2]) / 1000.0;
    return m;
  }
  if (kind == "cylinder") {
    need(2, "cylinder:DxH");
    return datasets::cylinder(mm[0] / 2000.0, mm[1] / 1000.0, 96);
  }
  if (kind == "sphere") {
    need(1, "sphere:D");
    return datasets::icosphere(4, mm[0] / 2000.0);
  }
  throw InputError(
      fmt::format("--shape: unknown shape '{}' (box:WxDxH, cylinder:DxH or sphere:D, millimetres)", shape));
}

}  // namespace meltlab::experiments
