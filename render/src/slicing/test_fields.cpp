// Seed 003's analytic gradient test fields (see slicing/test_fields.h).

#include <meltlab/render/slicing/test_fields.h>

#include <meltlab/core/error.h>

#include <algorithm>
#include <cmath>

namespace meltlab::render {

double test_field_distance(TestField field, int n, const Eigen::Vector3d& g, Eigen::Vector3d* gradient) {
  const double m = n - 1;  // the box [0, 1]³ spans n - 1 voxels
  const Eigen::Vector3d c = Eigen::Vector3d::Constant(0.5 * m);
  const Eigen::Vector3d d = g - c;
  if (field == TestField::kSphere) {
    const double r = d.norm();
    if (gradient) *gradient = r > 0 ? Eigen::Vector3d(d / r) : Eigen::Vector3d::UnitX();
    return r - 0.35 * m;
  }
  const double R = 0.28 * m, rr = 0.12 * m;  // major and minor radii; the ring in the xy plane
  const double q = std::hypot(d.x(), d.y());
  const Eigen::Vector3d ring = q > 0 ? Eigen::Vector3d(d.x() / q * R, d.y() / q * R, 0) : Eigen::Vector3d(R, 0, 0);
  const Eigen::Vector3d e = d - ring;
  const double len = e.norm();
  if (gradient) *gradient = len > 0 ? Eigen::Vector3d(e / len) : Eigen::Vector3d::UnitZ();
  return len - rr;
}

Volume make_test_field(TestField field, int n) {
  if (n < 8) throw InputError("test field: n must be >= 8");
  Volume v = Volume::allocate(n, n, n, SampleType::kFloat32, "test field");
  v.set_placement(SamplePlacement::kNodes);
  v.fit_to_box(Box3{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()});
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double sd = test_field_distance(field, n, Eigen::Vector3d(i, j, k));
        const double t = std::clamp((sd + 1.0) / 2.0, 0.0, 1.0);
        v.set_value(i, j, k, 1.0 - t * t * (3 - 2 * t));
      }
  return v;
}

}  // namespace meltlab::render
