#include <meltlab/experiments/render_json.h>
#include <meltlab/render/texture/assets.h>

namespace meltlab::experiments {
using json = nlohmann::json;

namespace {

json xyz(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

/// A file name, or what is used instead when there is none.
json source_of(const std::filesystem::path& file, const char* fallback) {
  return file.empty() ? json(fallback) : json(file.string());
}

json ice_json(const render::IceMaterial& m) {
  using render::FresnelMode, render::IceModel, render::SpecularTerm;
  return {{"model", m.model == IceModel::kMonograph ? "monograph" : "physical"},
          {"ca", m.ca},
          {"cd", m.cd},
          {"cs", m.cs},
          {"n_spec", m.n_spec},
          {"cr", m.cr},
          {"ct", m.ct},
          {"fresnel", m.fresnel == FresnelMode::kFull ? "full" : "schlick"},
          {"specular", m.specular == SpecularTerm::kRsV ? "RsV" : "RsL"},
          {"dispersion", m.dispersion},
          {"eta", m.eta},
          {"eta_rgb", m.eta_rgb},
          {"eta_convention", "air to ice eta_i/eta_t = 1/eta"},
          {"texture_scale", m.texture_scale},
          {"texture_source", source_of(m.texture_file, "procedural milky ice")},
          {"texture_tile", m.texture_tile},
          {"normal_map", m.normal_map},
          {"normal_map_space", "tangent, projected along the dominant axis"},
          {"normal_map_tile", m.normal_map_tile},
          {"normal_map_bump", m.normal_map_bump},
          {"normal_map_source", source_of(m.normal_map_file, "procedural")},
          {"absorption", m.absorption},
          {"max_internal_bounces", m.max_internal_bounces}};
}

json ground_json(const render::GroundMaterial& g) {
  return {{"z", g.z ? json(*g.z) : json(nullptr)},
          {"tile", g.tile},
          {"textured", g.textured},
          {"texture_source", source_of(g.texture_file, "procedural")},
          {"ca", g.ca},
          {"cd", g.cd},
          {"cs", g.cs},
          {"n_spec", g.n_spec},
          {"a", g.a},
          {"cr", g.cr},
          {"tilt_s", g.tilt_s},
          {"tilt_t", g.tilt_t},
          {"d", g.d},
          {"rs_uses_n_star", g.rs_uses_n_star},
          {"liquid", g.liquid},
          {"rim_offset_texels", 1}};
}

}  // namespace

json camera_json(const render::Camera& camera) {
  if (const auto* o = std::get_if<render::OrthographicTopDown>(&camera))
    return {{"type", "orthographic"},
            {"width", o->width},
            {"height", o->height},
            {"pixels_per_unit", o->pixels_per_unit},
            {"centre", {o->centre.x(), o->centre.y()}}};
  const auto& p = std::get<render::Pinhole>(camera);
  const Eigen::Matrix4d M = p.camera_from_world.matrix();
  json rows = json::array();
  for (int r = 0; r < 4; ++r) rows.push_back({M(r, 0), M(r, 1), M(r, 2), M(r, 3)});
  return {{"type", "pinhole"},
          {"width", p.width},
          {"height", p.height},
          {"fx", p.fx},
          {"fy", p.fy},
          {"cx", p.cx},
          {"cy", p.cy},
          {"distortion", p.distortion},
          {"camera_from_world", rows}};
}

// Seed 002's fog (render/fog/scene_fog.h): every fsa.* choice and the spotlights; null without fog.
json fog_json(const render::RenderScene& s) {
  if (!s.fog) return nullptr;
  json j;
  for (const auto& [k, v] : render::fog::describe_scene_fog(*s.fog)) j[k] = v;
  json lights = json::array();
  for (const auto& l : s.fog->spotlights) {
    json rings = json::array();
    const bool point = l.kind == render::fog::LightKind::kPoint;
    if (!point)
      for (const auto& r : l.profile)
        rings.push_back({{"half_angle_rad", r.half_angle_rad}, {"intensity", r.intensity}});
    lights.push_back({{"kind", point ? "point" : "spot"},
                      {"position", xyz(l.position)},
                      {"axis", xyz(l.axis)},
                      {"colour", xyz(l.colour)},
                      {"intensity", l.intensity},
                      {"profile", rings}});
  }
  j["spotlights"] = lights;
  return j;
}

json render_scene_json(const render::RenderScene& s) {
  json lights = json::array();
  for (const auto& l : s.lights) lights.push_back({{"to_light", xyz(l.to_light)}, {"colour", xyz(l.colour)}});
  return {
      {"camera", s.camera ? camera_json(*s.camera) : json("auto")},
      {"texture_filter", s.texture_filter == render::TextureFilter::kMipmap
                             ? "mipmap (OpenImageIO TextureSystem, ray differentials)"
                             : "bilinear"},
      {"lights", lights},
      {"ice", ice_json(s.ice)},
      {"ground", ground_json(s.ground)},
      {"environment",
       {{"type", "lat-long"},
        {"source", source_of(s.environment.file, "procedural")},
        {"layout", render::environment_layout_name(s.environment.layout)},
        {"width", s.environment.width},
        {"height", s.environment.height},
        {"to_sun", xyz(s.environment.to_sun)},
        {"sun_radiance", s.environment.sun_radiance}}},
      {"outputs",
       {{"exr", s.outputs.exr}, {"png", s.outputs.png}, {"exposure", s.outputs.exposure}, {"gamma", s.outputs.gamma}}},
      {"fog", fog_json(s)}};
}

}  // namespace meltlab::experiments
