// Scene description of the ice/liquid ray tracer (render_scene.h).

#include <meltlab/core/input_file.h>
#include <meltlab/render/render_scene.h>
#include <meltlab/core/yaml_keys.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <numbers>
#include <set>

namespace meltlab::render {

namespace {

std::string where(const YAML::Node& n, const std::string& source, const std::string& section) {
  const YAML::Mark mark = n.Mark();
  if (mark.line >= 0) return fmt::format("{}:{}: {}", source, mark.line + 1, section);
  return fmt::format("{}: {}", source, section);
}

// A mapping whose keys must all be known; typed reads with defaults at the read site.
class Section {
 public:
  Section(const YAML::Node& n, std::string at, const std::set<std::string>& allowed) : n_(n), at_(std::move(at)) {
    if (!n.IsMap()) throw InputError(fmt::format("{}: must be a mapping", at_));
    refuse_unknown_keys(n, at_, allowed);
  }
  bool has(const std::string& k) const { return static_cast<bool>(n_[k]); }
  const YAML::Node node(const std::string& k) const { return n_[k]; }
  const std::string& at() const { return at_; }

  double number(const std::string& k, double fallback, double lo = -INFINITY, double hi = INFINITY) const {
    if (!has(k)) return fallback;
    double x = 0;
    try {
      x = n_[k].as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(fmt::format("{}: '{}' must be a number (got '{}')", at_, k, n_[k].IsScalar() ? n_[k].Scalar() : "?"));
    }
    if (!std::isfinite(x)) throw InputError(fmt::format("{}: '{}' must be a finite number", at_, k));
    if (x < lo || x > hi) throw InputError(fmt::format("{}: '{}' must be in [{}, {}] (got {})", at_, k, lo, hi, x));
    return x;
  }
  int integer(const std::string& k, int fallback, int lo, int hi) const {
    if (!has(k)) return fallback;
    int v = 0;
    try {
      v = n_[k].as<int>();
    } catch (const YAML::Exception&) {
      throw InputError(fmt::format("{}: '{}' must be an integer (got '{}')", at_, k, n_[k].IsScalar() ? n_[k].Scalar() : "?"));
    }
    if (v < lo || v > hi) throw InputError(fmt::format("{}: '{}' must be in [{}, {}] (got {})", at_, k, lo, hi, v));
    return v;
  }
  bool flag(const std::string& k, bool fallback) const {
    if (!has(k)) return fallback;
    try {
      return n_[k].as<bool>();
    } catch (const YAML::Exception&) {
      throw InputError(fmt::format("{}: '{}' must be true or false", at_, k));
    }
  }
  Vec3d vec3(const std::string& k, const Vec3d& fallback, bool nonzero = false) const {
    if (!has(k)) return fallback;
    const YAML::Node v = n_[k];
    if (!v.IsSequence() || v.size() != 3) throw InputError(fmt::format("{}: '{}' must be a list of 3 numbers", at_, k));
    Vec3d out;
    for (int i = 0; i < 3; ++i) {
      try {
        out[i] = v[static_cast<std::size_t>(i)].as<double>();
      } catch (const YAML::Exception&) {
        throw InputError(fmt::format("{}: '{}' must be a list of 3 numbers", at_, k));
      }
    }
    if (!out.allFinite()) throw InputError(fmt::format("{}: '{}' must be finite", at_, k));
    if (nonzero && out.norm() == 0) throw InputError(fmt::format("{}: '{}' must not be the zero vector", at_, k));
    return out;
  }
  // An image file: relative paths are relative to the scene file's folder `base`; the file
  // must exist (it is read when the renderer is built).
  std::filesystem::path file(const std::string& k, const std::filesystem::path& base) const {
    if (!has(k)) return {};
    if (!n_[k].IsScalar() || n_[k].Scalar().empty()) throw InputError(fmt::format("{}: '{}' must be a file name", at_, k));
    std::filesystem::path f(n_[k].Scalar());
    if (f.is_relative()) f = base / f;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f, ec)) throw InputError(fmt::format("{}: '{}': no such image file {}", at_, k, f.string()));
    return f;
  }
  std::string choice(const std::string& k, const std::string& fallback, const std::set<std::string>& options) const {
    if (!has(k)) return fallback;
    if (!n_[k].IsScalar()) throw InputError(fmt::format("{}: '{}' must be a string", at_, k));
    const std::string v = n_[k].Scalar();
    if (!options.count(v)) {
      std::string list;
      for (const auto& a : options) list += (list.empty() ? "" : ", ") + a;
      throw InputError(fmt::format("{}: '{}' must be one of {} (got '{}')", at_, k, list, v));
    }
    return v;
  }

 private:
  const YAML::Node n_;
  std::string at_;
};

}  // namespace

RenderScene parse_render_scene(const YAML::Node& node, const std::string& source) {
  RenderScene s;
  if (!node || node.IsNull()) return s;
  const std::filesystem::path base = std::filesystem::path(source).parent_path();
  const Section top(node, where(node, source, "scene"),
                    {"camera", "width", "height", "texture_filter", "lights", "ice", "ground", "environment", "outputs"});
  if (top.has("camera")) s.camera = parse_camera(top.node("camera"), source);
  s.width = top.integer("width", s.width, 1, 16384);
  s.height = top.integer("height", s.height, 1, 16384);
  s.texture_filter = top.choice("texture_filter", "bilinear", {"bilinear", "mipmap"}) == "mipmap" ? TextureFilter::kMipmap
                                                                                                 : TextureFilter::kBilinear;
  if (top.has("lights")) {
    const YAML::Node list = top.node("lights");
    if (!list.IsSequence()) throw InputError(fmt::format("{}: 'lights' must be a list", top.at()));
    s.lights.clear();
    for (const auto& l : list) {
      const Section ls(l, where(l, source, "light"), {"to_light", "colour"});
      DirectionalLight d;
      d.to_light = ls.vec3("to_light", d.to_light, true);
      d.colour = ls.vec3("colour", d.colour);
      s.lights.push_back(d);
    }
  }
  if (top.has("ice")) {
    const Section is(top.node("ice"), where(top.node("ice"), source, "ice"),
                     {"model", "ca", "cd", "cs", "n_spec", "cr", "ct", "fresnel", "specular", "dispersion", "eta", "eta_rgb",
                      "texture_scale", "texture_file", "texture_tile", "normal_map", "normal_map_tile", "normal_map_bump", "normal_map_file", "absorption",
                      "max_internal_bounces"});
    IceMaterial& m = s.ice;
    m.model = is.choice("model", "monograph", {"monograph", "physical"}) == "physical" ? IceModel::kPhysical : IceModel::kMonograph;
    m.ca = is.number("ca", m.ca, 0, 100);
    m.cd = is.number("cd", m.cd, 0, 100);
    m.cs = is.number("cs", m.cs, 0, 100);
    m.n_spec = is.number("n_spec", m.n_spec, 0, 1e6);
    m.cr = is.number("cr", m.cr, 0, 100);
    m.ct = is.number("ct", m.ct, 0, 100);
    m.fresnel = is.choice("fresnel", "full", {"full", "schlick"}) == "schlick" ? FresnelMode::kSchlick : FresnelMode::kFull;
    m.specular = is.choice("specular", "RsV", {"RsV", "RsL"}) == "RsL" ? SpecularTerm::kRsL : SpecularTerm::kRsV;
    m.dispersion = is.flag("dispersion", m.dispersion);
    m.eta = is.number("eta", m.eta, 1.0, 4.0);
    const Vec3d e = is.vec3("eta_rgb", Vec3d(m.eta_rgb[0], m.eta_rgb[1], m.eta_rgb[2]));
    for (int c = 0; c < 3; ++c) {
      if (!(e[c] >= 1.0 && e[c] <= 4.0)) throw InputError(fmt::format("{}: 'eta_rgb' values must be in [1, 4]", is.at()));
      m.eta_rgb[static_cast<std::size_t>(c)] = e[c];
    }
    m.texture_scale = is.number("texture_scale", m.texture_scale, 0, INFINITY);
    m.texture_file = is.file("texture_file", base);
    m.texture_tile = is.number("texture_tile", m.texture_tile, 0, INFINITY);
    m.normal_map = is.flag("normal_map", m.normal_map);
    m.normal_map_tile = is.number("normal_map_tile", m.normal_map_tile, 0, INFINITY);
    m.normal_map_bump = is.number("normal_map_bump", m.normal_map_bump, 0, 100);
    m.normal_map_file = is.file("normal_map_file", base);
    if (!m.normal_map_file.empty()) m.normal_map = true;
    const Vec3d ab = is.vec3("absorption", Vec3d(m.absorption[0], m.absorption[1], m.absorption[2]));
    for (int c = 0; c < 3; ++c) {
      if (ab[c] < 0) throw InputError(fmt::format("{}: 'absorption' values must be >= 0", is.at()));
      m.absorption[static_cast<std::size_t>(c)] = ab[c];
    }
    m.max_internal_bounces = is.integer("max_internal_bounces", m.max_internal_bounces, 0, 64);
  }
  if (top.has("ground")) {
    const Section gs(top.node("ground"), where(top.node("ground"), source, "ground"),
                     {"z", "tile", "textured", "texture", "ca", "cd", "cs", "n_spec", "a", "cr", "tilt_s", "tilt_t", "d",
                      "rs_uses_n_star", "liquid"});
    GroundMaterial& g = s.ground;
    if (gs.has("z")) g.z = gs.number("z", 0.0);
    g.tile = gs.number("tile", g.tile, 0, INFINITY);
    g.textured = gs.flag("textured", g.textured);
    g.texture_file = gs.file("texture", base);
    g.ca = gs.number("ca", g.ca, 0, 100);
    g.cd = gs.number("cd", g.cd, 0, 100);
    g.cs = gs.number("cs", g.cs, 0, 100);
    g.n_spec = gs.number("n_spec", g.n_spec, 0, 1e6);
    g.a = gs.number("a", g.a, 0, 100);
    g.cr = gs.number("cr", g.cr, 0, 100);
    g.tilt_s = gs.number("tilt_s", g.tilt_s, 0, 100);
    g.tilt_t = gs.number("tilt_t", g.tilt_t, 0, 100);
    g.d = gs.number("d", g.d, 0, 10);
    g.rs_uses_n_star = gs.flag("rs_uses_n_star", g.rs_uses_n_star);
    g.liquid = gs.flag("liquid", g.liquid);
  }
  if (top.has("environment")) {
    const Section es(top.node("environment"), where(top.node("environment"), source, "environment"),
                     {"width", "height", "to_sun", "sun_radiance", "file", "layout"});
    s.environment.width = es.integer("width", s.environment.width, 8, 16384);
    s.environment.height = es.integer("height", s.environment.height, 4, 8192);
    s.environment.to_sun = es.vec3("to_sun", s.environment.to_sun, true);
    s.environment.sun_radiance = es.number("sun_radiance", s.environment.sun_radiance, 0, 1e6);
    s.environment.file = es.file("file", base);
    s.environment.layout = *environment_layout_from_name(
        es.choice("layout", "auto", {"auto", "latlong", "cube_3x2", "cube_1x6", "cross_horizontal", "cross_vertical"}));
  }
  if (top.has("outputs")) {
    const Section os(top.node("outputs"), where(top.node("outputs"), source, "outputs"), {"exr", "png", "exposure", "gamma"});
    s.outputs.exr = os.flag("exr", s.outputs.exr);
    s.outputs.png = os.flag("png", s.outputs.png);
    s.outputs.exposure = os.number("exposure", s.outputs.exposure, 1e-6, 1e6);
    s.outputs.gamma = os.number("gamma", s.outputs.gamma, 0.1, 10);
    if (!s.outputs.exr && !s.outputs.png) throw InputError(fmt::format("{}: at least one of 'exr' and 'png' must be true", os.at()));
  }
  return s;
}

RenderScene load_render_scene(const std::string& yaml_file) {
  const std::string text = read_text_file(yaml_file, "scene");
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw yaml_error(yaml_file, e, "YAML syntax error");
  }
  try {
    return parse_render_scene(root, yaml_file);
  } catch (const YAML::Exception& e) {
    throw yaml_error(yaml_file, e, "bad value");
  }
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

std::string describe_render_scene_json(const RenderScene& s) {
  const IceMaterial& m = s.ice;
  const GroundMaterial& g = s.ground;
  // A file name as a JSON string, or `fallback` (what is used instead) when there is none.
  auto source_of = [](const std::filesystem::path& f, const char* fallback) {
    if (f.empty()) return fmt::format("\"{}\"", fallback);
    std::string out = "\"";
    for (const char c : f.string()) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    return out + "\"";
  };
  std::string lights;
  for (const auto& l : s.lights)
    lights += fmt::format("{}{{\"to_light\": [{}, {}, {}], \"colour\": [{}, {}, {}]}}", lights.empty() ? "" : ", ", l.to_light.x(),
                          l.to_light.y(), l.to_light.z(), l.colour.x(), l.colour.y(), l.colour.z());
  return fmt::format(
      "{{\"camera\": {}, \"texture_filter\": \"{}\", \"lights\": [{}], "
      "\"ice\": {{\"model\": \"{}\", \"ca\": {}, \"cd\": {}, \"cs\": {}, \"n_spec\": {}, \"cr\": {}, \"ct\": {}, "
      "\"fresnel\": \"{}\", \"specular\": \"{}\", \"dispersion\": {}, \"eta\": {}, \"eta_rgb\": [{}, {}, {}], "
      "\"eta_convention\": \"air to ice eta_i/eta_t = 1/eta\", \"texture_scale\": {}, \"texture_source\": {}, "
      "\"texture_tile\": {}, \"normal_map\": {}, "
      "\"normal_map_space\": \"tangent, projected along the dominant axis\", \"normal_map_tile\": {}, \"normal_map_bump\": {}, "
      "\"normal_map_source\": {}, "
      "\"absorption\": [{}, {}, {}], \"max_internal_bounces\": {}}}, "
      "\"ground\": {{\"z\": {}, \"tile\": {}, \"textured\": {}, \"texture_source\": {}, \"ca\": {}, \"cd\": {}, \"cs\": {}, \"n_spec\": {}, \"a\": {}, \"cr\": {}, "
      "\"tilt_s\": {}, \"tilt_t\": {}, \"d\": {}, \"rs_uses_n_star\": {}, \"liquid\": {}, \"rim_offset_texels\": 1}}, "
      "\"environment\": {{\"type\": \"lat-long\", \"source\": {}, \"layout\": \"{}\", \"width\": {}, \"height\": {}, \"to_sun\": [{}, {}, {}], "
      "\"sun_radiance\": {}}}, \"outputs\": {{\"exr\": {}, \"png\": {}, \"exposure\": {}, \"gamma\": {}}}}}",
      s.camera ? describe_camera_json(*s.camera) : std::string("\"auto\""),
      s.texture_filter == TextureFilter::kMipmap ? "mipmap (OpenImageIO TextureSystem, ray differentials)" : "bilinear", lights,
      m.model == IceModel::kMonograph ? "monograph" : "physical", m.ca, m.cd, m.cs, m.n_spec, m.cr, m.ct,
      m.fresnel == FresnelMode::kFull ? "full" : "schlick", m.specular == SpecularTerm::kRsV ? "RsV" : "RsL", m.dispersion,
      m.eta, m.eta_rgb[0], m.eta_rgb[1], m.eta_rgb[2], m.texture_scale, source_of(m.texture_file, "procedural milky ice"), m.texture_tile, m.normal_map, m.normal_map_tile, m.normal_map_bump,
      source_of(m.normal_map_file, "procedural"), m.absorption[0], m.absorption[1], m.absorption[2], m.max_internal_bounces,
      g.z ? fmt::format("{}", *g.z) : std::string("null"), g.tile, g.textured, source_of(g.texture_file, "procedural"), g.ca, g.cd, g.cs, g.n_spec, g.a, g.cr, g.tilt_s, g.tilt_t, g.d,
      g.rs_uses_n_star, g.liquid, source_of(s.environment.file, "procedural"), environment_layout_name(s.environment.layout), s.environment.width, s.environment.height, s.environment.to_sun.x(), s.environment.to_sun.y(),
      s.environment.to_sun.z(), s.environment.sun_radiance, s.outputs.exr, s.outputs.png, s.outputs.exposure, s.outputs.gamma);
}

}  // namespace meltlab::render
