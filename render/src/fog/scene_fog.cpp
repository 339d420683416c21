// Seed 002's fog in the ice renderer: the scene's `fog:` section and the per-pixel pass
// (fog/scene_fog.h).

#include <meltlab/render/fog/scene_fog.h>

#include <meltlab/core/config.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace meltlab::render::fog {

namespace {

constexpr double kDeg = std::numbers::pi / 180;
constexpr int kMaxPhong = 500;  // fog_tables.cpp's largest exponent of G_n

int phong_exponent(double n) { return std::clamp(static_cast<int>(std::lround(n)), 1, kMaxPhong); }

Spotlight read_spotlight(const ConfigSection& s) {
  Spotlight l;
  // kind: point is Sun et al.'s isotropic point light (S3's comparison): no target, cone or rings.
  l.kind = s.get_choice("kind", "spot", {"spot", "point"}) == "point" ? LightKind::kPoint : LightKind::kSpot;
  if (!s.has("position")) s.fail("a spotlight needs 'position'");
  if (l.kind == LightKind::kPoint) {
    if (s.has("target") || s.has("half_angle_deg") || s.has("rings"))
      s.fail("a point light ('kind: point') takes no 'target', 'half_angle_deg' or 'rings'");
    l.position = s.get_vec3("position", Vec3::Zero());
    l.colour = s.get_vec3("colour", Vec3(1, 1, 1));
    if (l.colour.minCoeff() < 0) s.fail_at("colour", "'colour' values must be >= 0");
    l.intensity = s.get_in_range("intensity", 1.0, 0.0, 1e12);
    l.profile.clear();
    s.finish();
    return l;
  }
  if (!s.has("target")) s.fail("a spotlight needs 'target'");
  l.position = s.get_vec3("position", Vec3::Zero());
  const Vec3 target = s.get_vec3("target", Vec3::Zero());
  if ((target - l.position).norm() == 0) s.fail_at("target", "'target' must differ from 'position'");
  l.axis = (target - l.position).normalized();
  const double outer = s.get_in_range("half_angle_deg", 30.0, 0.01, 89.9);
  l.colour = s.get_vec3("colour", Vec3(1, 1, 1));
  if (l.colour.minCoeff() < 0) s.fail_at("colour", "'colour' values must be >= 0");
  l.intensity = s.get_in_range("intensity", 1.0, 0.0, 1e12);
  l.profile.clear();
  if (s.has("rings"))
    for (const ConfigSection& r : s.sections("rings")) {
      ConeStep c;
      c.half_angle_rad = r.get_in_range("half_angle_deg", 10.0, 0.01, 89.9) * kDeg;
      c.intensity = r.get_in_range("intensity", 1.0, 0.0, 1e6);
      r.finish();
      if (!l.profile.empty() && c.half_angle_rad <= l.profile.back().half_angle_rad)
        s.fail_at("rings", "'rings' must have increasing half_angle_deg");
      l.profile.push_back(c);
    }
  if (!l.profile.empty() && outer * kDeg <= l.profile.back().half_angle_rad)
    s.fail_at("half_angle_deg", "'half_angle_deg' (the outer cone) must exceed every ring's");
  l.profile.push_back(ConeStep{outer * kDeg, 1.0});
  s.finish();
  return l;
}

}  // namespace

SceneFog parse_scene_fog(const ConfigSection& fs) {
  SceneFog f;
  f.medium.kt = fs.get_in_range("kt", f.medium.kt, 0.0, 1e6);
  f.medium.albedo = fs.get_in_range("albedo", f.medium.albedo, 0.0, 1.0);
  f.far = fs.get_in_range("far", f.far, 1e-6, 1e12);
  if (!fs.has("spotlights")) fs.fail("'fog' needs 'spotlights' (a list)");
  for (const ConfigSection& s : fs.sections("spotlights")) f.spotlights.push_back(read_spotlight(s));
  if (f.spotlights.empty()) fs.fail_at("spotlights", "'spotlights' must not be empty");
  if (const auto ts = fs.optional_section("table")) {
    f.tables.n = ts->get_in_range("n", f.tables.n, 2, 4096);
    f.function = ts->get_choice("function", "H", {"F", "H"}) == "F" ? TableFunction::kF : TableFunction::kH;
    const std::vector<std::string> warps{"none", "sqrt", "cbrt", "sqrt_hi", "smooth"};
    f.tables.u_warp = parse_axis_warp(ts->get_choice("u_warp", "cbrt", warps), "u_warp");
    f.tables.v_warp = parse_axis_warp(ts->get_choice("v_warp", "sqrt_hi", warps), "v_warp");
    f.tables.v_interp = parse_interp_space(ts->get_choice("v_interp", "value", {"index", "value"}), "v_interp");
    ts->finish();
  } else {
    f.tables.u_warp = AxisWarp::kCbrt;
    f.tables.v_warp = AxisWarp::kSqrtHi;
    f.tables.v_interp = InterpSpace::kValue;
  }
  f.model.view_attenuation = fs.get_choice("view_attenuation", "apply", {"apply", "source_omit"}) == "apply"
                                 ? ViewAttenuation::kApply
                                 : ViewAttenuation::kSourceOmit;
  f.model.specular_args = fs.get_choice("specular_args", "mirror", {"mirror", "source"}) == "mirror"
                              ? SpecularArgs::kMirror
                              : SpecularArgs::kSource;
  f.model.cone_solver = fs.get_choice("cone_solver", "robust", {"robust", "source"}) == "robust" ? ConeSolver::kRobust
                                                                                                 : ConeSolver::kSource;
  f.model.surface_only_in_cone = fs.get("only_in_cone", f.model.surface_only_in_cone);
  fs.finish();
  return f;
}

std::vector<std::pair<std::string, std::string>> describe_scene_fog(const SceneFog& f) {
  std::vector<std::pair<std::string, std::string>> out = describe_options(f.model);
  out.emplace_back("fsa.medium.kt", fmt::format("{} per mesh unit", f.medium.kt));
  out.emplace_back("fsa.medium.albedo", fmt::format("{}", f.medium.albedo));
  out.emplace_back("fsa.table.N", fmt::format("{}", f.tables.n));
  out.emplace_back("fsa.table.function", table_function_name(f.function));
  out.emplace_back("fsa.table.axis_warp", axis_warp_name(f.tables.u_warp));
  out.emplace_back("fsa.table.v_warp", axis_warp_name(f.tables.v_warp));
  out.emplace_back("fsa.table.v_interp", interp_space_name(f.tables.v_interp));
  out.emplace_back("fsa.table.interp", "bilinear");
  out.emplace_back("fog.far", fmt::format("{} mesh units", f.far));
  out.emplace_back("fog.spotlights", fmt::format("{}", f.spotlights.size()));
  out.emplace_back("fog.materials", "Phong (cd, cs, n_spec) of the ice and the ground, diffuse colour white");
  return out;
}

FogShader::FogShader(SceneFog fog, const std::vector<double>& phong_exponents) : fog_(std::move(fog)) {
  airlight_ = build_fog_tables(fog_.tables, fog_.function, 1, false);
  airlight_.g_diffuse = g_table(1, fog_.tables);
  for (double n : phong_exponents) {
    const int k = phong_exponent(n);
    if (!specular_.count(k)) specular_.emplace(k, g_table(k, fog_.tables));
  }
}

FogMaterial FogShader::material(double kd, double ks, double exponent) {
  return FogMaterial{kd, ks, phong_exponent(exponent), Rgb(1, 1, 1)};
}

Rgb FogShader::apply(const Rgb& shaded, const Vec3& origin, const Vec3& dir, double m, const SurfaceHit* hit) const {
  const double dist = hit ? m : fog_.far;
  FogFunctions fn = airlight_.functions();
  fn.g_diffuse = &airlight_.g_diffuse;
  if (hit && hit->material) {
    const auto it = specular_.find(hit->material->n);
    if (it == specular_.end())
      throw InvariantError(fmt::format("fog: no G table for Phong exponent {}", hit->material->n));
    fn.g_specular = &it->second;
  }
  const double att = fog_.model.view_attenuation == ViewAttenuation::kApply ? std::exp(-fog_.medium.kt * dist) : 1.0;
  return att * shaded + fog_radiance(origin, dir, dist, hit, fog_.spotlights, fog_.medium, fn, fog_.model);
}

std::vector<std::string> FogShader::describe() const {
  std::vector<std::string> out{airlight_.airlight.describe(), airlight_.g_diffuse.describe() + " (the spec's G_0)"};
  for (const auto& [n, t] : specular_) out.push_back(t.describe());
  return out;
}

}  // namespace meltlab::render::fog
