// kl fields (monograph §3.4, Figs. 3.9–3.10): constant, point heat source with a falloff,
// pressure from a ground plane, a trilinear 3-D grid, and products / maxima / minima.

#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>
#include <meltlab/core/config.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/kl_field.h>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>

namespace meltlab::sim {

namespace {

std::string vec_json(const Vec3<double>& v) { return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z()); }

const char* falloff_name(Falloff f) {
  switch (f) {
    case Falloff::kGaussian:
      return "gaussian";
    case Falloff::kInverseSquare:
      return "inverse_square";
    case Falloff::kLinear:
      return "linear";
    case Falloff::kExponential:
      return "exponential";
  }
  return "?";
}

void check_unit(double x, const std::string& what) {
  if (!std::isfinite(x) || x < 0.0 || x > 1.0)
    throw InputError(fmt::format("{}: must lie in [0, 1] (got {})", what, x));
}
void check_leaf(double base, double strength, const std::string& where) {
  check_unit(base, where + ".base");
  check_unit(strength, where + ".strength");
  if (base + strength > 1.0 + 1e-12)
    throw InputError(
        fmt::format("{}: base + strength = {} exceeds 1 (kl must stay in [0, 1])", where, base + strength));
}
void check_positive(double x, const std::string& what) {
  if (!std::isfinite(x) || x <= 0.0) throw InputError(fmt::format("{}: must be a finite number > 0 (got {})", what, x));
}

class ConstantKl final : public KlField {
 public:
  explicit ConstantKl(double v) : v_(v) {}
  bool is_constant() const override { return true; }
  double value(const Vec3<double>&) const override { return v_; }
  std::string describe_json() const override { return fmt::format(R"({{"type": "constant", "value": {}}})", v_); }

 private:
  double v_;
};

class PointSourceKl final : public KlField {
 public:
  PointSourceKl(const Vec3<double>& c, double base, double strength, double radius, Falloff f)
      : c_(c), base_(base), strength_(strength), radius_(radius), falloff_(f) {}
  bool is_constant() const override { return strength_ == 0.0; }
  double value(const Vec3<double>& p) const override {
    const double x = (p - c_).norm() / radius_;
    double f = 0.0;
    switch (falloff_) {
      case Falloff::kGaussian:
        f = std::exp(-0.5 * x * x);
        break;
      case Falloff::kInverseSquare:
        f = 1.0 / (1.0 + x * x);
        break;
      case Falloff::kLinear:
        f = std::max(0.0, 1.0 - x);
        break;
      case Falloff::kExponential:
        f = std::exp(-x);
        break;
    }
    return base_ + strength_ * f;
  }
  std::string describe_json() const override {
    return fmt::format(
        R"({{"type": "point_source", "position": {}, "base": {}, "strength": {}, "radius": {}, "falloff": "{}"}})",
        vec_json(c_), base_, strength_, radius_, falloff_name(falloff_));
  }

 private:
  Vec3<double> c_;
  double base_, strength_, radius_;
  Falloff falloff_;
};

class GroundKl final : public KlField {
 public:
  GroundKl(const Vec3<double>& up, double height, double base, double strength, double scale)
      : up_(up.normalized()), height_(height), base_(base), strength_(strength), scale_(scale) {}
  bool is_constant() const override { return strength_ == 0.0; }
  double value(const Vec3<double>& p) const override {
    const double h = std::max(0.0, up_.dot(p) - height_);
    return base_ + strength_ * std::exp(-h / scale_);
  }
  std::string describe_json() const override {
    return fmt::format(
        R"({{"type": "ground", "up": {}, "height": {}, "base": {}, "strength": {}, "height_scale": {}}})",
        vec_json(up_), height_, base_, strength_, scale_);
  }

 private:
  Vec3<double> up_;
  double height_, base_, strength_, scale_;
};

class GridKl final : public KlField {
 public:
  GridKl(KlGrid g, std::string source) : g_(std::move(g)), source_(std::move(source)) {
    const auto [mn, mx] = std::minmax_element(g_.values.begin(), g_.values.end());
    constant_ = *mn == *mx && (g_.clamp_outside || g_.outside_value == *mn);
  }
  bool is_constant() const override { return constant_; }
  double value(const Vec3<double>& p) const override {
    double f[3];
    int i0[3];
    for (int d = 0; d < 3; ++d) {
      const double u = (p[d] - g_.origin[d]) / g_.spacing[d];
      const int n = g_.dims[static_cast<std::size_t>(d)];
      if (!(u >= 0.0 && u <= n - 1)) {
        if (!g_.clamp_outside) return g_.outside_value;
      }
      const double uc = std::clamp(u, 0.0, static_cast<double>(n - 1));
      int i = static_cast<int>(std::floor(uc));
      if (i >= n - 1) i = std::max(0, n - 2);
      i0[d] = i;
      f[d] = n == 1 ? 0.0 : uc - i;
    }
    auto at = [&](int i, int j, int k) {
      i = std::min(i, g_.dims[0] - 1);
      j = std::min(j, g_.dims[1] - 1);
      k = std::min(k, g_.dims[2] - 1);
      return g_.values[static_cast<std::size_t>(i + g_.dims[0] * (j + g_.dims[1] * k))];
    };
    double v = 0.0;
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
      if (w != 0.0) v += w * at(i0[0] + dx, i0[1] + dy, i0[2] + dz);
    }
    return v;
  }
  std::string describe_json() const override {
    return fmt::format(
        R"({{"type": "grid", "file": "{}", "dims": [{}, {}, {}], "origin": {}, "spacing": {}, "outside": {}}})",
        source_, g_.dims[0], g_.dims[1], g_.dims[2], vec_json(g_.origin), vec_json(g_.spacing),
        g_.clamp_outside ? std::string("\"clamp\"") : fmt::format("{}", g_.outside_value));
  }

 private:
  KlGrid g_;
  std::string source_;
  bool constant_ = false;
};

class CombinedKl final : public KlField {
 public:
  CombinedKl(Combine op, std::vector<KlFieldPtr> parts) : op_(op), parts_(std::move(parts)) {
    constant_ = std::all_of(parts_.begin(), parts_.end(), [](const KlFieldPtr& f) { return f->is_constant(); });
  }
  bool is_constant() const override { return constant_; }
  double value(const Vec3<double>& p) const override {
    double v = op_ == Combine::kProduct ? 1.0 : parts_.front()->value(p);
    for (std::size_t i = op_ == Combine::kProduct ? 0 : 1; i < parts_.size(); ++i) {
      const double x = parts_[i]->value(p);
      switch (op_) {
        case Combine::kProduct:
          v *= x;
          break;
        case Combine::kMax:
          v = std::max(v, x);
          break;
        case Combine::kMin:
          v = std::min(v, x);
          break;
      }
    }
    return v;
  }
  std::string describe_json() const override {
    std::string s = fmt::format(R"({{"type": "{}", "of": [)",
                                op_ == Combine::kProduct ? "product" : (op_ == Combine::kMax ? "max" : "min"));
    for (std::size_t i = 0; i < parts_.size(); ++i) s += (i ? ", " : "") + parts_[i]->describe_json();
    return s + "]}";
  }

 private:
  Combine op_;
  std::vector<KlFieldPtr> parts_;
  bool constant_ = false;
};

}  // namespace

KlFieldPtr make_constant_kl(double value) {
  check_unit(value, "kl constant");
  return std::make_shared<ConstantKl>(value);
}

KlFieldPtr make_point_source_kl(const Vec3<double>& position, double base, double strength, double radius,
                                Falloff falloff) {
  if (!position.allFinite()) throw InputError("kl point_source.position: must be finite");
  check_leaf(base, strength, "kl point_source");
  check_positive(radius, "kl point_source.radius");
  return std::make_shared<PointSourceKl>(position, base, strength, radius, falloff);
}

KlFieldPtr make_ground_kl(const Vec3<double>& up, double ground_height, double base, double strength,
                          double height_scale) {
  if (!up.allFinite() || up.norm() == 0.0) throw InputError("kl ground.up: must be a finite non-zero vector");
  if (!std::isfinite(ground_height)) throw InputError("kl ground.height: must be finite");
  check_leaf(base, strength, "kl ground");
  check_positive(height_scale, "kl ground.height_scale");
  return std::make_shared<GroundKl>(up, ground_height, base, strength, height_scale);
}

KlFieldPtr make_grid_kl(KlGrid grid, std::string source) {
  const std::string at = source.empty() ? std::string("kl grid") : source;
  for (int d = 0; d < 3; ++d) {
    if (grid.dims[static_cast<std::size_t>(d)] < 1) throw InputError(fmt::format("{}: dims must be >= 1", at));
    check_positive(grid.spacing[d], at + ": spacing");
  }
  if (!grid.origin.allFinite()) throw InputError(fmt::format("{}: origin must be finite", at));
  const std::size_t n = static_cast<std::size_t>(grid.dims[0]) * static_cast<std::size_t>(grid.dims[1]) *
                        static_cast<std::size_t>(grid.dims[2]);
  if (grid.values.size() != n)
    throw InputError(fmt::format("{}: {} values for {}x{}x{} = {} samples", at, grid.values.size(), grid.dims[0],
                                 grid.dims[1], grid.dims[2], n));
  for (std::size_t i = 0; i < n; ++i) check_unit(grid.values[i], fmt::format("{}: value #{}", at, i + 1));
  if (!grid.clamp_outside) check_unit(grid.outside_value, at + ": outside value");
  return std::make_shared<GridKl>(std::move(grid), std::move(source));
}

KlFieldPtr make_combined_kl(Combine op, std::vector<KlFieldPtr> parts) {
  if (parts.empty()) throw InputError("kl product/max/min: needs at least one field in 'of'");
  for (const auto& p : parts)
    if (!p) throw InputError("kl product/max/min: null field");
  return std::make_shared<CombinedKl>(op, std::move(parts));
}

// Grid file format (text, '#' comments allowed anywhere):
//   meltlab-kl-grid 1
//   dims NX NY NZ
//   origin X Y Z          (mesh units, object frame: position of sample (0,0,0))
//   spacing DX DY DZ      (mesh units)
//   values                (then NX*NY*NZ numbers in [0, 1], x fastest, then y, then z)
KlGrid read_kl_grid(const std::filesystem::path& file) {
  const std::string name = file.string();
  const std::string text = read_text_file(file, "kl grid");
  std::istringstream in(text);
  KlGrid g;
  std::string line;
  int line_no = 0;
  bool have_magic = false, have_dims = false, have_origin = false, have_spacing = false, in_values = false;
  std::size_t expected = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream ls(line);
    if (in_values) {
      std::string tok;
      while (ls >> tok) {
        char* end = nullptr;
        const double x = std::strtod(tok.c_str(), &end);
        if (end == tok.c_str() || *end != '\0' || !std::isfinite(x))
          throw InputError(fmt::format("{}:{}: '{}' is not a finite number", name, line_no, tok));
        if (x < 0.0 || x > 1.0) throw InputError(fmt::format("{}:{}: value {} outside [0, 1]", name, line_no, x));
        g.values.push_back(x);
      }
      continue;
    }
    std::string key;
    if (!(ls >> key)) continue;
    if (!have_magic) {
      int version = 0;
      if (key != "meltlab-kl-grid" || !(ls >> version) || version != 1)
        throw InputError(fmt::format("{}:{}: not a kl grid file (expected 'meltlab-kl-grid 1')", name, line_no));
      have_magic = true;
    } else if (key == "dims") {
      if (!(ls >> g.dims[0] >> g.dims[1] >> g.dims[2]) || g.dims[0] < 1 || g.dims[1] < 1 || g.dims[2] < 1)
        throw InputError(fmt::format("{}:{}: 'dims' needs three integers >= 1", name, line_no));
      const std::int64_t n = checked_mul(checked_mul(g.dims[0], g.dims[1]), g.dims[2]);
      check_count(fmt::format("{}:{}", name, line_no), "grid sample count", n < 0 ? INT64_MAX : n,
                  input_limits().volume_samples, "volume_samples");
      // Every value takes at least two bytes ("0 "): a header claiming more is lying.
      if (2 * n > static_cast<std::int64_t>(text.size()) + 1)
        throw InputError(fmt::format("{}:{}: dims {}x{}x{} need {} values; the file has only {} bytes", name, line_no,
                                     g.dims[0], g.dims[1], g.dims[2], n, text.size()));
      expected = static_cast<std::size_t>(n);
      have_dims = true;
    } else if (key == "origin") {
      if (!(ls >> g.origin.x() >> g.origin.y() >> g.origin.z()) || !g.origin.allFinite())
        throw InputError(fmt::format("{}:{}: 'origin' needs three finite numbers", name, line_no));
      have_origin = true;
    } else if (key == "spacing") {
      if (!(ls >> g.spacing.x() >> g.spacing.y() >> g.spacing.z()) || !(g.spacing.minCoeff() > 0) ||
          !g.spacing.allFinite())
        throw InputError(fmt::format("{}:{}: 'spacing' needs three finite numbers > 0", name, line_no));
      have_spacing = true;
    } else if (key == "values") {
      if (!have_dims || !have_origin || !have_spacing)
        throw InputError(fmt::format("{}:{}: 'values' before dims, origin and spacing", name, line_no));
      in_values = true;
      g.values.reserve(expected);
    } else {
      throw InputError(fmt::format("{}:{}: unknown key '{}'", name, line_no, key));
    }
  }
  if (!in_values) throw InputError(fmt::format("{}: no 'values' section", name));
  if (g.values.size() != expected)
    throw InputError(fmt::format("{}: expected {} values ({}x{}x{}), found {}", name, expected, g.dims[0], g.dims[1],
                                 g.dims[2], g.values.size()));
  return g;
}

namespace {

// The mesh's lowest point along `up` (its bounding box's extreme corner): "height: auto".
double lowest_along(const Vec3<double>& up, const KlContext& ctx) {
  const Vec3<double> u = up.normalized();
  double lo = 0.0;
  for (int c = 0; c < 8; ++c) {
    const Vec3<double> corner((c & 1) ? ctx.bbox_max.x() : ctx.bbox_min.x(),
                              (c & 2) ? ctx.bbox_max.y() : ctx.bbox_min.y(),
                              (c & 4) ? ctx.bbox_max.z() : ctx.bbox_min.z());
    lo = c == 0 ? u.dot(corner) : std::min(lo, u.dot(corner));
  }
  return lo;
}

Falloff falloff_from(const ConfigSection& k) {
  const std::string f = k.get<std::string>("falloff", "gaussian");
  if (f == "gaussian") return Falloff::kGaussian;
  if (f == "inverse_square") return Falloff::kInverseSquare;
  if (f == "linear") return Falloff::kLinear;
  if (f == "exponential") return Falloff::kExponential;
  k.fail_at("falloff", fmt::format("unknown falloff '{}' (gaussian, inverse_square, linear, exponential)", f));
}

KlFieldPtr parse_field(const ConfigValue& node, const KlContext& ctx);

KlFieldPtr parse_mapping(const ConfigSection& k, const KlContext& ctx) {
  if (!k.has("type")) k.fail("kl field without 'type'");
  const std::string type = k.require<std::string>("type");
  if (type == "constant") return make_constant_kl(k.require<double>("value"));
  if (type == "point_source") {
    const Falloff falloff = falloff_from(k);
    return make_point_source_kl(k.require_vec3("position"), k.get("base", 0.0), k.get("strength", 1.0),
                                k.require<double>("radius"), falloff);
  }
  if (type == "ground") {
    const Vec3<double> up = k.get_vec3("up", Vec3<double>(0, 0, 1));
    if (!(up.norm() > 0)) k.fail_at("up", "'up' must be non-zero");
    const auto height = k.optional_value("height");
    const double h = !height || height->scalar() == "auto" ? lowest_along(up, ctx) : height->as<double>();
    return make_ground_kl(up, h, k.get("base", 0.0), k.get("strength", 1.0), k.require<double>("height_scale"));
  }
  if (type == "grid") {
    std::filesystem::path file = k.require<std::string>("file");
    if (file.is_relative()) file = ctx.base_dir / file;
    KlGrid g = read_kl_grid(file);
    const auto outside = k.optional_value("outside");
    g.clamp_outside = !outside || outside->scalar() == "clamp";
    if (!g.clamp_outside) g.outside_value = outside->as<double>();
    return make_grid_kl(std::move(g), file.string());
  }
  if (type == "product" || type == "max" || type == "min") {
    const auto of = k.optional_value("of");
    if (!of || !of->is_sequence() || of->items().empty()) k.fail(fmt::format("'{}' needs a non-empty list 'of'", type));
    std::vector<KlFieldPtr> parts;
    for (const ConfigValue& child : of->items()) parts.push_back(parse_field(child, ctx));
    const Combine op = type == "product" ? Combine::kProduct : (type == "max" ? Combine::kMax : Combine::kMin);
    return make_combined_kl(op, std::move(parts));
  }
  k.fail_at("type",
            fmt::format("unknown kl field type '{}' (constant, point_source, ground, grid, product, max, min)", type));
}

KlFieldPtr parse_field(const ConfigValue& node, const KlContext& ctx) {
  if (node.is_null()) node.fail("empty kl field");
  if (!node.is_scalar() && !node.is_map()) node.fail("a kl field is a number or a mapping with 'type'");
  try {
    return node.is_scalar() ? make_constant_kl(node.as<double>()) : parse_mapping(node.section(), ctx);
  } catch (const InputError& e) {
    // The make_* checks name the field, not the file: say where it is.
    const std::string msg = e.what();
    if (msg.rfind(node.file(), 0) == 0) throw;
    node.fail(msg);
  }
}

}  // namespace

KlFieldPtr parse_kl_field(const YAML::Node& node, const std::string& source, const KlContext& ctx) {
  const ConfigValue kl(node, source, "kl");
  KlFieldPtr field = parse_field(kl, ctx);
  kl.finish();
  return field;
}

KlFieldPtr load_kl_field(const std::filesystem::path& file, const KlContext& ctx) {
  const ConfigSection root = load_config(file, "kl field");
  if (!root.has("kl")) root.fail("expected a top-level key 'kl'");
  KlContext c = ctx;
  if (c.base_dir.empty()) c.base_dir = file.parent_path();
  KlFieldPtr field = parse_field(root.value("kl"), c);
  root.finish();
  return field;
}

}  // namespace meltlab::sim
