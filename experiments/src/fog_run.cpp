// `meltlab fog render` (experiments/fog.h).

#include <meltlab/core/time.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/experiments/fog.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/render/fog/fog_frame.h>
#include <meltlab/render/texture/assets.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <chrono>

namespace meltlab::experiments {

namespace fog = render::fog;
using nlohmann::json;

namespace {}  // namespace

fog::FogScene fog_scene_by_name(const std::string& name, double kt, int width, int height, int lights) {
  if (name == "sphere") return fog::scene_sphere(kt, width, height);
  if (name == "street") return fog::scene_street(kt, width, height, lights);
  if (name == "lamp_spot") return fog::scene_lamp(kt, width, height, false);
  if (name == "lamp_point") return fog::scene_lamp(kt, width, height, true);
  throw InputError(fmt::format("--scene: unknown scene '{}' (sphere, street, lamp_spot, lamp_point)", name));
}

fog::FogModelOptions fog_model_options(const std::string& view_attenuation, const std::string& specular_args,
                                       const std::string& cone_solver, const std::string& terms) {
  fog::FogModelOptions o;
  if (view_attenuation != "apply" && view_attenuation != "source_omit")
    throw InputError(fmt::format("--view-attenuation: '{}' (apply, source_omit)", view_attenuation));
  o.view_attenuation = view_attenuation == "apply" ? fog::ViewAttenuation::kApply : fog::ViewAttenuation::kSourceOmit;
  if (specular_args != "mirror" && specular_args != "source")
    throw InputError(fmt::format("--specular-args: '{}' (mirror, source)", specular_args));
  o.specular_args = specular_args == "mirror" ? fog::SpecularArgs::kMirror : fog::SpecularArgs::kSource;
  if (cone_solver != "robust" && cone_solver != "source")
    throw InputError(fmt::format("--cone-solver: '{}' (robust, source)", cone_solver));
  o.cone_solver = cone_solver == "robust" ? fog::ConeSolver::kRobust : fog::ConeSolver::kSource;
  if (terms == "no_airlight") {
    o.airlight = false;
  } else if (terms == "direct") {
    o.airlight = false;
    o.surface_fog = false;
  } else if (terms != "all") {
    throw InputError(fmt::format("--terms: '{}' (all, no_airlight, direct)", terms));
  }
  return o;
}

fog::TableFunction fog_table_function(const std::string& name) {
  if (name == "F") return fog::TableFunction::kF;
  if (name == "H") return fog::TableFunction::kH;
  throw InputError(fmt::format("--table-function: '{}' (F, H)", name));
}

json describe_model(const fog::FogModelOptions& o, const fog::FogTableSet& tables, const fog::FogMedium& medium) {
  json j;
  for (const auto& [k, v] : fog::describe_options(o)) j[k] = v;
  j["fsa.medium.kt"] = medium.kt;
  j["fsa.medium.albedo"] = medium.albedo;
  j["fsa.table.N"] = tables.options.n;
  j["fsa.table.interp"] = "bilinear";
  j["fsa.table.axis_warp"] = fog::axis_warp_name(tables.options.u_warp);
  j["fsa.table.v_warp"] = fog::axis_warp_name(tables.options.v_warp);
  j["fsa.table.v_interp"] = fog::interp_space_name(tables.options.v_interp);
  j["fsa.table.F.domain"] = fmt::format("v in [0, π/2], u in [0, {}]", tables.options.u_max);
  j["fsa.table.G.domain"] = fmt::format("T in [0, {}], θ in [0, π]", tables.options.t_max);
  j["fsa.table.beyond_domain"] = tables.function == fog::TableFunction::kF
                                     ? "clamp, flag"
                                     : "H: K = H (1 + u tan v) continued as K(u_max, v), flag";
  j["fsa.table.function"] = fog::table_function_name(tables.function);
  j["tables"] = tables.describe();
  return j;
}

FogRenderResult run_fog_render(const FogRenderOptions& o) {
  if (o.width < 1 || o.height < 1 || o.width > 8192 || o.height > 8192)
    throw InputError("--width/--height must be in [1, 8192]");
  if (!(o.kt >= 0) || o.kt > 100) throw InputError(fmt::format("--kt = {}: must be in [0, 100] (1/m)", o.kt));
  if (o.table_n < 2 || o.table_n > 4096) throw InputError("--table-n must be in [2, 4096]");
  if (o.lights < 1 || o.lights > 64) throw InputError("--lights must be in [1, 64]");
  fog::FogScene scene = fog_scene_by_name(o.scene, o.kt, o.width, o.height, o.lights);
  const fog::FogModelOptions model = fog_model_options(o.view_attenuation, o.specular_args, o.cone_solver, o.terms);
  fog::TableOptions to;
  to.n = o.table_n;
  to.u_warp = fog::parse_axis_warp(o.u_warp, "--u-warp");
  to.v_warp = fog::parse_axis_warp(o.v_warp, "--v-warp");
  to.v_interp = fog::parse_interp_space(o.v_interp, "--v-interp");
  const fog::TableFunction function = fog_table_function(o.table_function);
  RunFolder folder(o.out_dir, RunFolderOptions{"--out", "render.json", "fog render", o.overwrite});
  Provenance provenance = start_provenance("fog render", o.command_line);
  const fog::FogTableSet tables = fog::build_fog_tables(to, function, scene.material.n);
  FogRenderResult r;
  auto t0 = std::chrono::steady_clock::now();
  const fog::GBuffer g = fog::trace_analytic(scene);
  r.visibility_ms = ms_since(t0);
  t0 = std::chrono::steady_clock::now();
  fog::ShadeStats stats;
  const ImageF img = fog::shade_fog(g, scene, tables.functions(), model, &stats);
  r.shading_ms = ms_since(t0);
  r.lit_pixels = stats.lit_pixels;
  r.lookups = stats.lookups.lookups;
  r.clamped = stats.lookups.clamped;
  render::write_png(folder.path() / "image.png", img, o.exposure);
  render::write_exr(folder.path() / "image.exr", img);
  json j;
  j["scene"] = scene.name;
  j["width"] = o.width;
  j["height"] = o.height;
  j["lights"] = scene.lights.size();
  j["model"] = describe_model(model, tables, scene.medium);
  j["terms"] = o.terms;
  j["exposure"] = o.exposure;
  j["timing_ms"] = {{"tables", tables.build_ms}, {"visibility", r.visibility_ms}, {"shading", r.shading_ms}};
  j["lit_pixels"] = r.lit_pixels;
  j["table_lookups"] = {{"total", r.lookups}, {"beyond_domain", r.clamped}};
  commit_run(folder, std::move(j), provenance);
  return r;
}

}  // namespace meltlab::experiments
