#pragma once
// The local melt-rate coefficient kl : R³ -> [0, 1] (monograph §3.4, Eq. 3.8; Figs. 3.9,
// 3.10). It stands for non-uniform heating (a warm air stream, a lamp, a heat source) and
// for pressure (the body's own weight on the ground). Fields are built from a YAML config
// and are immutable once built, so TBB tasks can share them.
//
// Every leaf keeps its value in [0, 1] by construction (base + strength <= 1), so products,
// maxima and minima do too. A constant field is recognised by the cycle and never
// evaluated per vertex.
//
// YAML (all lengths in mesh units, object frame; unknown keys are errors):
//   kl: 0.8                                   # shorthand for a constant
//   kl: {type: constant, value: 0.8}
//   kl: {type: point_source, position: [x,y,z], base: 0.2, strength: 0.8,
//        radius: 0.02, falloff: gaussian}     # gaussian | inverse_square | linear | exponential
//   kl: {type: ground, up: [0,0,1], height: auto, base: 0.3, strength: 0.7,
//        height_scale: 0.005}                 # height: auto = the mesh's lowest point
//   kl: {type: grid, file: heat.klgrid, outside: clamp}   # or outside: 0.5
//   kl: {type: product | max | min, of: [field, field, ...]}

#include <meltlab/sim/mesh.h>

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace meltlab::sim {

class KlField {
 public:
  virtual ~KlField() = default;
  /// True if the value does not depend on position (then `value` ignores its argument).
  virtual bool is_constant() const = 0;
  /// kl at a point (object frame, mesh units); in [0, 1].
  virtual double value(const Vec3<double>& p) const = 0;
  /// The field as resolved YAML/JSON text (all defaults and 'auto' values filled in), for run.json.
  virtual std::string describe_json() const = 0;

  /// kl at every live vertex: out[k] = value(P[k]) where alive[k]; dead slots untouched.
  template <class Real>
  void evaluate(std::span<const Vec3<Real>> P, std::span<const std::uint8_t> alive, std::span<Real> out) const {
    for (std::size_t k = 0; k < P.size(); ++k)
      if (alive[k]) out[k] = static_cast<Real>(value(P[k].template cast<double>()));
  }
};

using KlFieldPtr = std::shared_ptr<const KlField>;

/// What 'auto' values in a config resolve against (the initial mesh).
struct KlContext {
  Vec3<double> bbox_min = Vec3<double>::Zero();
  Vec3<double> bbox_max = Vec3<double>::Zero();
  std::filesystem::path base_dir;  ///< relative grid files are resolved against this
};

enum class Falloff { kGaussian, kInverseSquare, kLinear, kExponential };

KlFieldPtr make_constant_kl(double value);
/// base + strength * f(|p - position| / radius), f(0) = 1, f decreasing to 0.
KlFieldPtr make_point_source_kl(const Vec3<double>& position, double base, double strength, double radius,
                                Falloff falloff);
/// base + strength * exp(-h / height_scale), h = max(0, (p - ground point) . up).
KlFieldPtr make_ground_kl(const Vec3<double>& up, double ground_height, double base, double strength,
                          double height_scale);

/// Regular 3-D grid of kl samples at origin + (i, j, k) * spacing, trilinear between them.
struct KlGrid {
  std::array<int, 3> dims{0, 0, 0};
  Vec3<double> origin = Vec3<double>::Zero();
  Vec3<double> spacing = Vec3<double>::Ones();
  std::vector<double> values;  ///< x fastest: values[i + nx * (j + ny * k)]
  bool clamp_outside = true;   ///< true: nearest edge sample; false: `outside_value`
  double outside_value = 0.0;
};
KlFieldPtr make_grid_kl(KlGrid grid, std::string source = {});
/// Reads a grid file (format in kl_field.cpp: "meltlab-kl-grid 1", dims, origin, spacing,
/// values). Throws InputError "<file>:<line>: <problem>".
KlGrid read_kl_grid(const std::filesystem::path& file);

enum class Combine { kProduct, kMax, kMin };
KlFieldPtr make_combined_kl(Combine op, std::vector<KlFieldPtr> parts);

/// Builds a field from a YAML node (the value of the `kl:` key). `source` names the file
/// for error messages.
KlFieldPtr parse_kl_field(const YAML::Node& node, const std::string& source, const KlContext& ctx);
/// Reads a YAML file whose top-level key `kl:` holds the field.
KlFieldPtr load_kl_field(const std::filesystem::path& file, const KlContext& ctx);

}  // namespace meltlab::sim
