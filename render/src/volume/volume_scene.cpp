// The scene file of `meltlab volume render` (see volume/volume_scene.h).

#include <meltlab/render/volume/volume_scene.h>

#include <meltlab/core/config.h>
#include <meltlab/core/error.h>
#include <meltlab/render/volume/volume_io.h>

#include <fmt/format.h>

namespace meltlab::render {

namespace fs = std::filesystem;

namespace {

Rgb colour(const ConfigSection& c, const std::string& key, const Rgb& fallback) {
  const auto v = c.optional_value(key);
  if (!v) return fallback;
  if (v->is_scalar()) {
    const double x = v->as<double>();
    return Rgb::Constant(x);
  }
  return v->as_vec3();
}

VolumeGenerateOptions parse_generate(const ConfigSection& g) {
  VolumeGenerateOptions o;
  o.kind = parse_volume_kind(
      g.get_choice("kind", "turbulence_box", {"turbulence_box", "turbulence_sphere", "fireball", "constant"}),
      g.where());
  if (g.has("size") && g.has("dims")) g.fail("give 'size' or 'dims', not both");
  if (g.has("dims")) {
    const auto d = g.require_numbers("dims", 3, 3);
    for (double x : d)
      if (!(x >= 1 && x <= 4096 && x == std::floor(x)))
        g.fail_at("dims", "'dims' must be three whole numbers in [1, 4096]");
    o.nx = int(d[0]), o.ny = int(d[1]), o.nz = int(d[2]);
  } else {
    o.nx = o.ny = o.nz = g.get_in_range<int>("size", 64, 1, 4096);
  }
  o.noise.octaves = g.get_in_range<int>("octaves", 4, 1, 16);
  o.noise.gain = g.get_in_range<double>("gain", 2.0, 1e-6, 1e6);
  o.noise.lacunarity = g.get_in_range<double>("lacunarity", 2.0, 1e-6, 1e6);
  o.noise.base_frequency = g.get_in_range<double>("base_frequency", 4.0, 1e-6, 1e6);
  const std::string clip = g.get_choice("clip", "per_octave", {"per_octave", "sum_only", "none"});
  o.noise.clip = clip == "per_octave" ? NoiseClip::kPerOctave
                 : clip == "sum_only" ? NoiseClip::kSumOnly
                                      : NoiseClip::kNone;
  o.noise.seed = std::uint64_t(g.get_in_range<std::int64_t>("seed", 0, 0, std::int64_t(1) << 62));
  o.falloff =
      g.get_choice("falloff", "linear", {"linear", "none"}) == "none" ? SphereFalloff::kNone : SphereFalloff::kLinear;
  o.constant = g.get<double>("constant", 1.0);
  const std::string q = g.get_choice("quantization", "float32", {"float32", "uint8", "uint16"});
  o.storage = q == "uint8" ? SampleType::kUint8 : q == "uint16" ? SampleType::kUint16 : SampleType::kFloat32;
  return o;
}

VolumeLight parse_light(const ConfigSection& c) {
  VolumeLight l;
  const std::string type = c.get_choice("type", "point", {"point", "directional"});
  l.type = type == "point" ? LightType::kPoint : LightType::kDirectional;
  if (l.type == LightType::kPoint) {
    l.position = c.require_vec3("position");
    l.falloff = c.get_choice("falloff", "none", {"none", "inv_square"}) == "inv_square" ? LightFalloff::kInverseSquare
                                                                                        : LightFalloff::kNone;
  } else {
    l.to_light = c.require_vec3("to_light");
    if (!(l.to_light.norm() > 0)) c.fail_at("to_light", "'to_light' must not be the zero vector");
    l.to_light.normalize();
  }
  l.intensity = colour(c, "intensity", Rgb::Ones());
  if ((l.intensity.array() < 0).any()) c.fail_at("intensity", "'intensity' must be >= 0");
  return l;
}

}  // namespace

VolumeScene parse_volume_scene(const ConfigSection& c, const fs::path& base_dir) {
  VolumeScene scene;
  VolumeRenderSettings& s = scene.settings;
  const std::string model = c.get_choice("model", "emission_absorption",
                                         {"absorption", "emission", "emission_absorption", "hg", "hg_attenuated"});
  s.model = model == "absorption"            ? OpticalModel::kAbsorption
            : model == "emission"            ? OpticalModel::kEmission
            : model == "emission_absorption" ? OpticalModel::kEmissionAbsorption
            : model == "hg"                  ? OpticalModel::kHG
                                             : OpticalModel::kHGAttenuated;
  // --- the volume ---
  const ConfigSection v = c.section("volume");
  if (v.has("generate") == v.has("file")) v.fail("give exactly one of 'generate' and 'file'");
  if (v.has("generate")) scene.volume.generate = parse_generate(v.section("generate"));
  if (v.has("file")) {
    const fs::path f = v.require<std::string>("file");
    scene.volume.file = f.is_absolute() ? f : base_dir / f;
  }
  if (const auto b = v.optional_section("box")) {
    const Eigen::Vector3d centre = b->get_vec3("centre", Eigen::Vector3d::Zero());
    const Eigen::Vector3d size = b->require_vec3("size");
    if (!(size.minCoeff() > 0)) b->fail_at("size", "'size' must be three numbers > 0");
    scene.volume.box = Box3{centre - 0.5 * size, centre + 0.5 * size};
  } else if (scene.volume.generate) {
    scene.volume.box = Box3{Eigen::Vector3d::Constant(-150), Eigen::Vector3d::Constant(150)};  // the seed's Box300
  }
  s.address =
      v.get_choice("address", "clamp", {"clamp", "wrap"}) == "wrap" ? VolumeAddress::kWrap : VolumeAddress::kClamp;
  // --- camera ---
  scene.camera = parse_camera(c.section("camera"));
  if (!std::holds_alternative<Pinhole>(scene.camera)) c.fail_at("camera", "the volume renderer needs a pinhole camera");
  // --- sampling and quadrature ---
  if (const auto sm = c.optional_section("sampling")) {
    s.samples = sm->get_in_range<int>("n", 100, 1, 1 << 20);
    const std::string rule = sm->get_choice("ds_rule", "diag_over_n", {"diag_over_n", "fit_segment"});
    s.step_rule = rule == "fit_segment" ? StepRule::kFitSegment : StepRule::kDiagonalOverN;
    s.step = sm->get_in_range<double>("step", 0.0, 0.0, 1e300);
    if (s.step_rule == StepRule::kFitSegment && !(s.step > 0)) sm->fail("ds_rule fit_segment needs 'step' > 0");
    const std::string off = sm->get_choice("first_offset", "zero", {"zero", "half", "jitter"});
    s.first_offset = off == "half" ? FirstOffset::kHalf : off == "jitter" ? FirstOffset::kJitter : FirstOffset::kZero;
    s.jitter_seed = std::uint64_t(sm->get_in_range<std::int64_t>("seed", 1, 0, std::int64_t(1) << 62));
    s.include_last_partial = sm->get_choice("last_partial", "drop", {"drop", "weight"}) == "weight";
  }
  const std::string quad = c.get_choice("quadrature", "inclusive", {"inclusive", "exclusive", "exponential"});
  s.quadrature = quad == "exclusive"     ? Quadrature::kExclusive
                 : quad == "exponential" ? Quadrature::kExponential
                                         : Quadrature::kInclusive;
  // --- optics ---
  if (const auto o = c.optional_section("optics")) {
    s.kappa = o->get_in_range<double>("kappa", 1.0, 0.0, 1e12);
    s.gamma = o->get_in_range<double>("gamma", 1.0, 1e-6, 1e6);
    s.albedo = o->get_in_range<double>("albedo", 0.9, 0.0, 1e6);
    s.hg_c = o->get_in_range<double>("hg_c", 0.5, -0.999999, 0.999999);
    s.emission = colour(*o, "emission", s.emission);
    s.emission_rim = colour(*o, "emission_rim", s.emission_rim);
    s.emission_field = o->get_choice("emission_field", "constant", {"constant", "radial"}) == "radial"
                           ? EmissionField::kRadial
                           : EmissionField::kConstant;
    s.emission_scale_by_ds = o->get<bool>("emission_scale_by_ds", true);
    s.kappa_in_source = o->get<bool>("kappa_in_source", false);
    s.kappa_in_brdf = o->get<bool>("kappa_in_brdf", false);
    s.ambient = colour(*o, "ambient", Rgb::Zero());
    if ((s.ambient.array() < 0).any()) o->fail_at("ambient", "'ambient' must be >= 0");
    if (!s.emission_scale_by_ds && s.quadrature == Quadrature::kExponential)
      o->fail_at("emission_scale_by_ds", "'emission_scale_by_ds: false' needs the inclusive or exclusive quadrature");
  }
  // --- lights ---
  if (c.has("lights"))
    for (const ConfigSection& l : c.sections("lights")) s.lights.push_back(parse_light(l));
  // --- shadows, acceleration, rays ---
  if (const auto sh = c.optional_section("shadow")) {
    s.shadow =
        sh->get_choice("method", "march", {"march", "cache"}) == "cache" ? ShadowMethod::kCache : ShadowMethod::kMarch;
    s.shadow_step = sh->get_in_range<double>("step", 0.0, 0.0, 1e300);
    s.shadow_start_offset = sh->get_in_range<double>("start_offset", 0.5, 0.0, 1.0);
    s.shadow_cache_build = sh->get_choice("cache_build", "sweep", {"sweep", "march"}) == "march"
                               ? ShadowCacheBuild::kMarch
                               : ShadowCacheBuild::kSweep;
    s.shadow_cache_scale = sh->get_in_range<double>("cache_scale", 1.0, 0.05, 8.0);
  }
  if (const auto a = c.optional_section("acceleration")) {
    s.ert_transmittance = a->get_in_range<double>("ert_transmittance", 0.0, 0.0, 0.999);
    s.skip_empty = a->get<bool>("skip_empty", true);
  }
  if (const auto r = c.optional_section("rays")) {
    s.ray_generation = r->get_choice("method", "analytic", {"analytic", "two_pass"}) == "two_pass"
                           ? RayGeneration::kTwoPass
                           : RayGeneration::kAnalytic;
    s.camera_inside = r->get_choice("camera_inside", "reject", {"reject", "start_at_eye"}) == "start_at_eye"
                          ? CameraInside::kStartAtEye
                          : CameraInside::kReject;
  }
  // --- output and timing ---
  if (const auto out = c.optional_section("output")) {
    scene.mode = out->get_choice("mode", "standalone", {"standalone", "composite"}) == "composite"
                     ? VolumeOutputMode::kComposite
                     : VolumeOutputMode::kStandalone;
    s.background = colour(*out, "background", Rgb::Zero());
    if (out->has("background_image")) {
      const fs::path f = out->require<std::string>("background_image");
      scene.background_image = f.is_absolute() ? f : base_dir / f;
    }
    if (scene.mode == VolumeOutputMode::kComposite && scene.background_image.empty())
      out->fail("composite mode needs 'background_image'");
    if (scene.mode == VolumeOutputMode::kStandalone && !scene.background_image.empty())
      out->fail_at("background_image", "'background_image' is for mode: composite");
    scene.exposure = out->get_in_range<double>("exposure", 1.0, 0.0, 1e12);
  }
  if (const auto t = c.optional_section("timing")) {
    scene.warmup_frames = t->get_in_range<int>("warmup", 3, 0, 1000);
    scene.timed_frames = t->get_in_range<int>("frames", 20, 1, 100000);
  }
  return scene;
}

VolumeScene read_volume_scene(const fs::path& file) {
  const ConfigSection c = load_config(file, "volume scene");
  VolumeScene scene = parse_volume_scene(c, file.parent_path());
  c.finish();
  return scene;
}

Volume load_scene_volume(const VolumeScene& scene) {
  Volume v = scene.volume.generate ? generate_volume(*scene.volume.generate) : read_volume(scene.volume.file);
  if (scene.volume.box) v.fit_to_box(*scene.volume.box);
  return v;
}

std::vector<std::pair<std::string, std::string>> describe_vlr(const VolumeScene& scene, const Volume& volume) {
  const VolumeRenderSettings& s = scene.settings;
  std::vector<std::pair<std::string, std::string>> r;
  auto add = [&](const std::string& k, const std::string& v) { r.emplace_back("vlr." + k, v); };
  auto num = [](double x) { return fmt::format("{:.17g}", x); };
  auto rgb = [&](const Rgb& c) { return fmt::format("[{}, {}, {}]", num(c.x()), num(c.y()), num(c.z())); };
  add("model", optical_model_name(s.model));
  add("sampling.n", std::to_string(s.samples));
  add("sampling.ds_rule", s.step_rule == StepRule::kFitSegment ? "fit_segment" : "diag_over_n");
  add("sampling.ds", num(primary_step(volume, s)));
  add("sampling.first_offset", s.first_offset == FirstOffset::kZero   ? "0"
                               : s.first_offset == FirstOffset::kHalf ? "0.5 ds"
                                                                      : fmt::format("jitter (seed {})", s.jitter_seed));
  add("sampling.last_partial", s.include_last_partial ? "weight" : "drop");
  add("quad.extinction_inclusive", s.quadrature == Quadrature::kInclusive ? "true" : "false");
  add("quad.rule", quadrature_name(s.quadrature));
  add("emission.scale_by_ds", s.emission_scale_by_ds ? "true" : "false");
  add("emission.kappa_in_source", s.kappa_in_source ? "true" : "false");
  add("scatter.kappa_in_brdf", s.kappa_in_brdf ? "true" : "false");
  add("phase.cos_convention", "cos theta = (light propagation direction) . (direction to the eye); c > 0 forward");
  add("errata.isotropic", "isotropic phase = 1/(4 pi)");
  add("hg.c", num(s.hg_c));
  add("albedo", num(s.albedo));
  add("kappa", num(s.kappa));
  add("gamma", num(s.gamma));
  add("emission.color", rgb(s.emission));
  add("ambient", rgb(s.ambient) + " (uniform radiance in-scattered, unshadowed; HG models)");
  add("emission.color_field",
      s.emission_field == EmissionField::kRadial ? "radial to " + rgb(s.emission_rim) : "constant");
  const auto lights = effective_lights(volume, s);
  add("light.count", std::to_string(lights.size()));
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const auto& l = lights[i];
    const std::string p = fmt::format("light[{}].", i);
    add(p + "type", l.type == LightType::kPoint ? "point" : "directional");
    add(p + (l.type == LightType::kPoint ? "pos" : "to_light"),
        rgb(l.type == LightType::kPoint ? l.position : l.to_light));
    add(p + "intensity", rgb(l.intensity));
    add(p + "falloff", l.falloff == LightFalloff::kInverseSquare ? "inv_square" : "none");
  }
  add("shadow.method", s.shadow == ShadowMethod::kCache ? "cache" : "march");
  add("shadow.step", num(s.shadow_step > 0 ? s.shadow_step : primary_step(volume, s)));
  add("shadow.start_offset", num(s.shadow_start_offset) + " shadow steps");
  add("shadow.end", "min(box exit, light distance)");
  if (s.shadow == ShadowMethod::kCache) {
    add("shadow.cache_build", s.shadow_cache_build == ShadowCacheBuild::kSweep ? "sweep" : "march");
    add("shadow.cache_scale", num(s.shadow_cache_scale));
  }
  add("slab.swap", "per axis (required)");
  add("tex.address", s.address == VolumeAddress::kWrap ? "wrap" : "clamp");
  add("tex.filter", "trilinear");
  add("data.quantization", sample_type_name(volume.type()));
  add("gradient.scale", "raw central differences");
  if (scene.volume.generate) {
    const auto& g = *scene.volume.generate;
    add("noise.octaves", std::to_string(g.noise.octaves));
    add("noise.gain", num(g.noise.gain));
    add("noise.lacunarity", num(g.noise.lacunarity));
    add("noise.base_freq", num(g.noise.base_frequency));
    add("noise.clip_mode", g.noise.clip == NoiseClip::kPerOctave ? "per_octave"
                           : g.noise.clip == NoiseClip::kSumOnly ? "sum_only"
                                                                 : "none");
    add("noise.seed", std::to_string(g.noise.seed));
    add("noise.permutation", "Perlin 2002 reference");
    add("sphere.falloff", g.falloff == SphereFalloff::kLinear ? "linear 1 - r/R" : "none");
  }
  add("output.mode", scene.mode == VolumeOutputMode::kComposite ? "composite" : "standalone");
  add("raygen.method", s.ray_generation == RayGeneration::kTwoPass ? "two_pass" : "analytic");
  add("camera.inside", s.camera_inside == CameraInside::kStartAtEye ? "start_at_eye" : "reject");
  add("ert.transmittance", num(s.ert_transmittance));
  add("ess", s.skip_empty ? "macrocells of 4^3 samples (exact)" : "off");
  add("timing.protocol", fmt::format("{} warm-up frames, median of {}", scene.warmup_frames, scene.timed_frames));
  add("errata.grid_points", "64^3 = 262144");
  add("errata.config_ref", "config 1");
  add("errata.slab_formula", "reconstructed: t_near = (-d/2 - S)/v");
  return r;
}

}  // namespace meltlab::render
