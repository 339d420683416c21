// Scene description of the ice/liquid ray tracer (render_scene.h).

#include <meltlab/render/render_scene.h>
#include <meltlab/core/config.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <numbers>

namespace meltlab::render {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// An image file: relative paths are relative to the scene file's folder `base`; the file must
// exist (it is read when the renderer is built). Empty when the key is absent.
std::filesystem::path image_file(const ConfigSection& c, const std::string& key, const std::filesystem::path& base) {
  const auto name = c.optional<std::string>(key);
  if (!name) return {};
  if (name->empty()) c.fail_at(key, fmt::format("'{}' must be a file name", key));
  std::filesystem::path f(*name);
  if (f.is_relative()) f = base / f;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(f, ec))
    c.fail_at(key, fmt::format("'{}': no such image file {}", key, f.string()));
  return f;
}

// A direction or colour of three finite numbers; `nonzero` for directions.
Vec3d vec3(const ConfigSection& c, const std::string& key, const Vec3d& fallback, bool nonzero = false) {
  const Vec3d v = c.get_vec3(key, fallback);
  if (nonzero && v.norm() == 0) c.fail_at(key, fmt::format("'{}' must not be the zero vector", key));
  return v;
}

// The Phong coefficients of a material (Eq. 2.13): ambient, diffuse, specular and exponent.
void read_phong(const ConfigSection& c, double& ca, double& cd, double& cs, double& n_spec) {
  ca = c.get_in_range("ca", ca, 0.0, 100.0);
  cd = c.get_in_range("cd", cd, 0.0, 100.0);
  cs = c.get_in_range("cs", cs, 0.0, 100.0);
  n_spec = c.get_in_range("n_spec", n_spec, 0.0, 1e6);
}

void read_ice(const ConfigSection& is, const std::filesystem::path& base, IceMaterial& m) {
  m.model = is.get_choice("model", "monograph", {"monograph", "physical"}) == "physical" ? IceModel::kPhysical
                                                                                         : IceModel::kMonograph;
  read_phong(is, m.ca, m.cd, m.cs, m.n_spec);
  m.cr = is.get_in_range("cr", m.cr, 0.0, 100.0);
  m.ct = is.get_in_range("ct", m.ct, 0.0, 100.0);
  m.fresnel =
      is.get_choice("fresnel", "full", {"full", "schlick"}) == "schlick" ? FresnelMode::kSchlick : FresnelMode::kFull;
  m.specular = is.get_choice("specular", "RsV", {"RsV", "RsL"}) == "RsL" ? SpecularTerm::kRsL : SpecularTerm::kRsV;
  m.dispersion = is.get("dispersion", m.dispersion);
  m.eta = is.get_in_range("eta", m.eta, 1.0, 4.0);
  const Vec3d e = vec3(is, "eta_rgb", Vec3d(m.eta_rgb[0], m.eta_rgb[1], m.eta_rgb[2]));
  for (int c = 0; c < 3; ++c) {
    if (!(e[c] >= 1.0 && e[c] <= 4.0)) is.fail_at("eta_rgb", "'eta_rgb' values must be in [1, 4]");
    m.eta_rgb[static_cast<std::size_t>(c)] = e[c];
  }
  m.texture_scale = is.get_in_range("texture_scale", m.texture_scale, 0.0, kInf);
  m.texture_file = image_file(is, "texture_file", base);
  m.texture_tile = is.get_in_range("texture_tile", m.texture_tile, 0.0, kInf);
  m.normal_map = is.get("normal_map", m.normal_map);
  m.normal_map_tile = is.get_in_range("normal_map_tile", m.normal_map_tile, 0.0, kInf);
  m.normal_map_bump = is.get_in_range("normal_map_bump", m.normal_map_bump, 0.0, 100.0);
  m.normal_map_file = image_file(is, "normal_map_file", base);
  if (!m.normal_map_file.empty()) m.normal_map = true;
  const Vec3d ab = vec3(is, "absorption", Vec3d(m.absorption[0], m.absorption[1], m.absorption[2]));
  for (int c = 0; c < 3; ++c) {
    if (ab[c] < 0) is.fail_at("absorption", "'absorption' values must be >= 0");
    m.absorption[static_cast<std::size_t>(c)] = ab[c];
  }
  m.max_internal_bounces = is.get_in_range("max_internal_bounces", m.max_internal_bounces, 0, 64);
}

void read_ground(const ConfigSection& gs, const std::filesystem::path& base, GroundMaterial& g) {
  if (const auto z = gs.optional<double>("z")) g.z = *z;
  g.tile = gs.get_in_range("tile", g.tile, 0.0, kInf);
  g.textured = gs.get("textured", g.textured);
  g.texture_file = image_file(gs, "texture", base);
  read_phong(gs, g.ca, g.cd, g.cs, g.n_spec);
  g.a = gs.get_in_range("a", g.a, 0.0, 100.0);
  g.cr = gs.get_in_range("cr", g.cr, 0.0, 100.0);
  g.tilt_s = gs.get_in_range("tilt_s", g.tilt_s, 0.0, 100.0);
  g.tilt_t = gs.get_in_range("tilt_t", g.tilt_t, 0.0, 100.0);
  g.d = gs.get_in_range("d", g.d, 0.0, 10.0);
  g.rs_uses_n_star = gs.get("rs_uses_n_star", g.rs_uses_n_star);
  g.liquid = gs.get("liquid", g.liquid);
}

void read_environment(const ConfigSection& es, const std::filesystem::path& base, EnvironmentOptions& env) {
  env.width = es.get_in_range("width", env.width, 8, 16384);
  env.height = es.get_in_range("height", env.height, 4, 8192);
  env.to_sun = vec3(es, "to_sun", env.to_sun, true);
  env.sun_radiance = es.get_in_range("sun_radiance", env.sun_radiance, 0.0, 1e6);
  env.file = image_file(es, "file", base);
  env.layout = *environment_layout_from_name(es.get_choice(
      "layout", "auto", {"auto", "latlong", "cube_3x2", "cube_1x6", "cross_horizontal", "cross_vertical"}));
}

void read_outputs(const ConfigSection& os, RenderOutputs& out) {
  out.exr = os.get("exr", out.exr);
  out.png = os.get("png", out.png);
  out.exposure = os.get_in_range("exposure", out.exposure, 1e-6, 1e6);
  out.gamma = os.get_in_range("gamma", out.gamma, 0.1, 10.0);
  if (!out.exr && !out.png) os.fail("at least one of 'exr' and 'png' must be true");
}

}  // namespace

RenderScene parse_render_scene(const YAML::Node& node, const std::string& source) {
  RenderScene s;
  if (!node || node.IsNull()) return s;
  const std::filesystem::path base = std::filesystem::path(source).parent_path();
  const ConfigSection top(node, source);
  if (const auto camera = top.optional_section("camera")) s.camera = parse_camera(*camera);
  s.width = top.get_in_range("width", s.width, 1, 16384);
  s.height = top.get_in_range("height", s.height, 1, 16384);
  s.texture_filter = top.get_choice("texture_filter", "bilinear", {"bilinear", "mipmap"}) == "mipmap"
                         ? TextureFilter::kMipmap
                         : TextureFilter::kBilinear;
  if (top.has("lights")) {
    s.lights.clear();
    for (const ConfigSection& ls : top.sections("lights")) {
      DirectionalLight d;
      d.to_light = vec3(ls, "to_light", d.to_light, true);
      d.colour = vec3(ls, "colour", d.colour);
      s.lights.push_back(d);
    }
  }
  if (const auto is = top.optional_section("ice")) read_ice(*is, base, s.ice);
  if (const auto gs = top.optional_section("ground")) read_ground(*gs, base, s.ground);
  if (const auto es = top.optional_section("environment")) read_environment(*es, base, s.environment);
  if (const auto os = top.optional_section("outputs")) read_outputs(*os, s.outputs);
  if (const auto fs = top.optional_section("fog")) s.fog = fog::parse_scene_fog(*fs);
  top.finish();
  return s;
}

RenderScene load_render_scene(const std::string& yaml_file) {
  return parse_render_scene(load_yaml_file(yaml_file, "scene"), yaml_file);
}

Pinhole auto_camera(const Vec3d& lower, const Vec3d& upper, int width, int height) {
  const Vec3d centre = 0.5 * (lower + upper);
  const double radius = std::max(0.5 * (upper - lower).norm(), 1e-9);
  const double fx = 1.0 * std::max(width, height);  // ≈ 53° across the longer side
  const double half_fov = std::atan(0.5 * std::min(width, height) / fx);
  const double dist = 1.15 * radius / std::sin(half_fov);
  const double elev = 30.0 * std::numbers::pi / 180.0;
  const Vec3d eye = centre + dist * Vec3d(0.0, -std::cos(elev), std::sin(elev));
  return Pinhole::look_at(width, height, fx, eye, centre, Vec3d(0, 0, 1));
}

}  // namespace meltlab::render
