// Seed 003's procedural CT phantom (see volume/ct_phantom.h).

#include <meltlab/render/volume/ct_phantom.h>

#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <numbers>

namespace meltlab::render {

namespace {

using Vec3 = Eigen::Vector3d;

struct Ellipsoid {
  Vec3 centre;  ///< fraction of L from the box centre
  Vec3 semi;    ///< fraction of L
  bool contains(const Vec3& p, const Vec3& L) const {
    const Vec3 q = (p - centre.cwiseProduct(L)).cwiseQuotient(semi.cwiseProduct(L));
    return q.squaredNorm() < 1.0;
  }
};

const Vec3 kSkin(0.45, 0.40, 0.50);
constexpr double kFatThickness = 0.02, kBoneThickness = 0.03;
const Vec3 kMuscleSemi(0.07, 0.12, 0.15), kMuscleCentre(0.20, 0.05, -0.05);
const Vec3 kCavitySemi(0.05, 0.05, 0.06), kCavityCentre(0.08, -0.25, -0.10);

Vec3 mirrored_x(const Vec3& c) { return Vec3(-c.x(), c.y(), c.z()); }

}  // namespace

double ct_phantom_hu(const Vec3& p, const Vec3& L) {
  const Vec3 zero = Vec3::Zero();
  const Ellipsoid e0{zero, kSkin};
  if (!e0.contains(p, L)) return hu::kAir;
  const Ellipsoid e1{zero, kSkin - Vec3::Constant(kFatThickness)};
  if (!e1.contains(p, L)) return hu::kFat;
  const Ellipsoid e2{zero, kSkin - Vec3::Constant(kFatThickness + kBoneThickness)};
  if (!e2.contains(p, L)) return hu::kBone;
  for (const Vec3& c : {kCavityCentre, mirrored_x(kCavityCentre)})
    if (Ellipsoid{c, kCavitySemi}.contains(p, L)) return hu::kAir;
  for (const Vec3& c : {kMuscleCentre, mirrored_x(kMuscleCentre)})
    if (Ellipsoid{c, kMuscleSemi}.contains(p, L)) return hu::kMuscle;
  return hu::kWater;
}

ScalarVolume generate_ct_phantom(const CtPhantomOptions& o) {
  for (int d : o.dims)
    if (d < 2)
      throw InputError(fmt::format("ct_phantom: dims {} x {} x {} need at least 2 samples per axis", o.dims[0],
                                   o.dims[1], o.dims[2]));
  if (!(o.spacing.minCoeff() > 0) || !o.spacing.allFinite())
    throw InputError("ct_phantom: the spacing must be three finite numbers > 0");
  if (!(o.noise_sigma_hu >= 0) || !std::isfinite(o.noise_sigma_hu))
    throw InputError("ct_phantom: the noise sigma must be a finite number >= 0");
  ScalarVolume v = ScalarVolume::allocate(o.dims, ScalarType::kInt16, "ct_phantom");
  v.spacing = o.spacing;
  const Vec3 n(o.dims[0], o.dims[1], o.dims[2]);
  const Vec3 L = (n - Vec3::Ones()).cwiseProduct(o.spacing);
  const Vec3 half = 0.5 * (n - Vec3::Ones());
  const std::uint64_t key = splitmix64(o.seed ^ 0x43545068616e746dULL);  // "CTPhantm"
  auto* out = reinterpret_cast<std::int16_t*>(v.bytes.data());
  tbb::parallel_for(tbb::blocked_range<int>(0, o.dims[2]), [&](const tbb::blocked_range<int>& r) {
    for (int k = r.begin(); k < r.end(); ++k)
      for (int j = 0; j < o.dims[1]; ++j)
        for (int i = 0; i < o.dims[0]; ++i) {
          const std::int64_t idx = i + std::int64_t(o.dims[0]) * (j + std::int64_t(o.dims[1]) * k);
          const Vec3 p = (Vec3(i, j, k) - half).cwiseProduct(o.spacing);
          double value = ct_phantom_hu(p, L);
          if (o.noise_sigma_hu > 0) {
            const std::uint64_t h1 = splitmix64(key + 2 * std::uint64_t(idx));
            const std::uint64_t h2 = splitmix64(key + 2 * std::uint64_t(idx) + 1);
            const double u1 = unit_from_bits(h1), u2 = unit_from_bits(h2);
            value += o.noise_sigma_hu * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
          }
          const double rounded = std::round(value);
          out[idx] = static_cast<std::int16_t>(rounded < -32768 ? -32768 : rounded > 32767 ? 32767 : rounded);
        }
  });
  return v;
}

std::map<std::string, std::string> describe_ct_phantom(const CtPhantomOptions& o) {
  return {{"kind", "ct_phantom"},
          {"dims", fmt::format("{}x{}x{}", o.dims[0], o.dims[1], o.dims[2])},
          {"spacing", fmt::format("{:.17g},{:.17g},{:.17g}", o.spacing.x(), o.spacing.y(), o.spacing.z())},
          {"noise_sigma_hu", fmt::format("{:.17g}", o.noise_sigma_hu)},
          {"seed", std::to_string(o.seed)},
          {"sample_type", "int16"},
          {"hu", "air -1000, fat -120, water 0, muscle 40, bone 1000 (source Table 1)"},
          {"geometry",
           "skin 0.45x0.40x0.50 (semi-axes, fractions of the box), fat 0.02, bone shell 0.03, "
           "muscles (0.07,0.12,0.15) at (+-0.20,0.05,-0.05), cavities (0.05,0.05,0.06) at "
           "(+-0.08,-0.25,-0.10)"},
          {"noise", "Gaussian, splitmix64(seed, sample index) + Box-Muller"}};
}

}  // namespace meltlab::render
