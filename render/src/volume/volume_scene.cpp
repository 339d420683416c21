// The scene file of `meltlab volume render` (see volume/volume_scene.h).

#include <meltlab/render/volume/volume_scene.h>

#include <meltlab/core/config.h>
#include <meltlab/core/error.h>
#include <meltlab/render/volume/volume_io.h>

#include <fmt/format.h>

namespace meltlab::render {

namespace fs = std::filesystem;

namespace {

bool src_is_shapes(const VolumeScene& scene) {
  return scene.volume.generate && scene.volume.generate->kind == VolumeKind::kShapes;
}

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
      g.get_choice("kind", "turbulence_box",
                   {"turbulence_box", "turbulence_sphere", "fireball", "constant", "shapes", "skull", "ct_phantom"}),
      g.where());
  if (g.has("size") && g.has("dims")) g.fail("give 'size' or 'dims', not both");
  if (g.has("dims")) {
    const auto d = g.require_numbers("dims", 3, 3);
    for (double x : d)
      if (!(x >= 1 && x <= 4096 && x == std::floor(x)))
        g.fail_at("dims", "'dims' must be three whole numbers in [1, 4096]");
    o.nx = int(d[0]), o.ny = int(d[1]), o.nz = int(d[2]);
  } else if (o.kind == VolumeKind::kCtPhantom && !g.has("size")) {
    o.nx = o.ny = 256;  // the source's CT head: 113 slices of 256 x 256
    o.nz = 113;
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
  const auto seed = g.optional_value("seed");
  const std::int64_t seed_value = seed ? seed->as_in_range<std::int64_t>(0, std::int64_t(1) << 62) : -1;
  o.noise.seed = seed_value >= 0 ? std::uint64_t(seed_value) : 0;
  if (o.kind == VolumeKind::kShapes || o.kind == VolumeKind::kSkull) {
    // Seed 001 (clv.gen.*): the spec's seed 2 for the shapes, 1 for the phantom's noise.
    o.shapes.seed = seed_value >= 0 ? std::uint64_t(seed_value) : (o.kind == VolumeKind::kShapes ? 2 : 1);
    o.shapes.count = g.get_in_range<int>("shapes", 70, 0, 1000000);
    o.shapes.sample = g.get_in_range<int>("sample", 100, 10, 245);
    o.shapes.object_size = g.get_in_range<int>("object_size", 70, 1, 1 << 20);
  }
  if (o.kind == VolumeKind::kCtPhantom) {
    // Seed 003 (vsi.testgen): the noise seed (default 1) and sigma in HU.
    o.ct.seed = seed_value >= 0 ? std::uint64_t(seed_value) : 1;
    o.ct.noise_sigma_hu = g.get_in_range<double>("noise_hu", 20.0, 0.0, 1e4);
    o.ct.spacing = g.get_vec3("spacing", Eigen::Vector3d(1, 1, 2));
    if (!(o.ct.spacing.minCoeff() > 0)) g.fail_at("spacing", "'spacing' must be three numbers > 0");
  }
  o.falloff =
      g.get_choice("falloff", "linear", {"linear", "none"}) == "none" ? SphereFalloff::kNone : SphereFalloff::kLinear;
  o.constant = g.get<double>("constant", 1.0);
  const std::string q = g.get_choice("quantization", "float32", {"float32", "uint8", "uint16"});
  o.storage = q == "uint8" ? SampleType::kUint8 : q == "uint16" ? SampleType::kUint16 : SampleType::kFloat32;
  return o;
}

void parse_transfer_function(const ConfigSection& t, VolumeScene& scene) {
  TfModel& m = scene.settings.tf;
  if (const auto table = t.optional_value("table")) {
    if (table->is_scalar()) {
      const std::string name = table->as<std::string>();
      try {
        m.table = TransferFunction::named(name, table->where());
      } catch (const InputError&) {
        table->fail(fmt::format("unknown table '{}' (shapes, skull, or a list of ranges)", name));
      }
    } else {
      std::vector<TfRange> ranges;
      for (const ConfigValue& item : table->items()) {
        const ConfigSection r = item.section();
        TfRange range;
        try {
          parse_tf_bounds(r.require<std::string>("range"), range, "range");
        } catch (const InputError& e) {
          r.fail_at("range", e.what());
        }
        range.rgb = r.require_vec3("rgb");
        range.alpha = r.require_in_range<double>("alpha", 0.0, 1.0);
        ranges.push_back(range);
      }
      try {
        m.table = TransferFunction(ranges, "custom", "transfer_function.table");
      } catch (const InputError& e) {
        table->fail(e.what());
      }
    }
  }
  m.reference_step = t.get_in_range<double>("reference_step", 0.0, 0.0, 1e300);
  m.exponent = t.get_choice("opacity_exponent", "s_over_s0", {"s_over_s0", "s0_over_s"}) == "s0_over_s"
                   ? OpacityExponent::kReferenceOverStep
                   : OpacityExponent::kStepOverReference;
  if (const auto sh = t.optional_section("shading")) {
    m.shading.enabled = sh->get<bool>("enabled", true);
    m.shading.gradient = sh->get_choice("gradient", "central", {"central", "one_sided"}) == "one_sided"
                             ? GradientScheme::kOneSided
                             : GradientScheme::kCentral;
    m.shading.threshold = sh->get_in_range<double>("threshold", 2.0, 0.0, 1e300);
    m.shading.light_dir = sh->get_vec3("light_dir", Eigen::Vector3d(-4, -3, -2));
    if (!(m.shading.light_dir.norm() > 0)) sh->fail_at("light_dir", "'light_dir' must not be the zero vector");
    m.shading.light_dir.normalize();
    m.shading.ka = sh->get_in_range<double>("ka", 0.16, 0.0, 1e6);
    m.shading.q = sh->get_in_range<double>("q", 128.0, 0.0, 1e6);
    m.shading.ks = sh->get_in_range<double>("ks", 120.0, 0.0, 1e6);
  }
  scene.tf_output = t.get_choice("output", "premultiplied", {"premultiplied", "source_double"}) == "source_double"
                        ? TfOutput::kSourceDouble
                        : TfOutput::kPremultiplied;
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
  if (c.get_choice("method", "ray_casting", {"ray_casting", "slicing"}) == "slicing") {
    for (const char* key : {"model", "sampling", "quadrature", "optics", "transfer_function", "lights", "shadow",
                            "acceleration", "traversal", "rays"})
      if (c.has(key)) c.fail_at(key, fmt::format("'{}' is for method: ray_casting (slicing reads 'slicing:')", key));
    scene.slicing = parse_slicing_scene(c.section("slicing"));
  } else if (c.has("slicing")) {
    c.fail_at("slicing", "'slicing' is for method: slicing");
  }
  VolumeRenderSettings& s = scene.settings;
  const std::string model =
      c.get_choice("model", "emission_absorption",
                   {"absorption", "emission", "emission_absorption", "hg", "hg_attenuated", "transfer_function"});
  s.model = model == "absorption"            ? OpticalModel::kAbsorption
            : model == "emission"            ? OpticalModel::kEmission
            : model == "emission_absorption" ? OpticalModel::kEmissionAbsorption
            : model == "hg"                  ? OpticalModel::kHG
            : model == "hg_attenuated"       ? OpticalModel::kHGAttenuated
                                             : OpticalModel::kTransferFunction;
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
  } else if (scene.volume.generate && scene.volume.generate->kind != VolumeKind::kShapes &&
             scene.volume.generate->kind != VolumeKind::kSkull &&
             scene.volume.generate->kind != VolumeKind::kCtPhantom) {
    scene.volume.box = Box3{Eigen::Vector3d::Constant(-150), Eigen::Vector3d::Constant(150)};  // the seed's Box300
  }
  s.address =
      v.get_choice("address", "clamp", {"clamp", "wrap"}) == "wrap" ? VolumeAddress::kWrap : VolumeAddress::kClamp;
  scene.volume.memory = v.get_choice("memory", "mmap", {"mmap", "ram"}) == "ram" ? ClvMemory::kRam : ClvMemory::kMmap;
  scene.volume.samples = v.get_choice("samples", "stored", {"stored", "float32"}) == "float32" ? ClvSamples::kFloat32
                                                                                               : ClvSamples::kStored;
  const std::string layout = v.get_choice("layout", "as_stored", {"as_stored", "linear", "blocked"});
  scene.volume.layout = layout == "linear"    ? VolumeLayout::kLinear
                        : layout == "blocked" ? VolumeLayout::kBlocked
                                              : VolumeLayout::kAsStored;
  scene.volume.block_side = v.get_in_range<int>("block_side", 16, 2, 255);
  // Seed 003's medical files (.vlb, .nrrd, .nhdr): vsi.data.norm_source and vsi.data.window_units.
  const std::string norm = v.get_choice("normalise", "scanned", {"scanned", "header", "window", "none"});
  scene.volume.read.norm = norm == "header"   ? NormSource::kHeader
                           : norm == "window" ? NormSource::kWindow
                           : norm == "none"   ? NormSource::kNone
                                              : NormSource::kScanned;
  scene.volume.read.window_units = v.get_choice("window_units", "fraction", {"fraction", "value"}) == "value"
                                       ? VlbWindowUnits::kValue
                                       : VlbWindowUnits::kFraction;
  if (v.has("normalise") && !(scene.volume.generate ? false : is_medical_volume_file(scene.volume.file)))
    v.fail_at("normalise", "'normalise' applies to .vlb, .nrrd and .nhdr files only");
  // --- camera ---
  scene.camera = parse_camera(c.section("camera"));
  if (!std::holds_alternative<Pinhole>(scene.camera)) c.fail_at("camera", "the volume renderer needs a pinhole camera");
  // --- sampling and quadrature ---
  if (const auto sm = c.optional_section("sampling")) {
    s.samples = sm->get_in_range<int>("n", 100, 1, 1 << 20);
    const std::string rule = sm->get_choice("ds_rule", "diag_over_n", {"diag_over_n", "fit_segment", "fixed_step"});
    s.step_rule = rule == "fit_segment"  ? StepRule::kFitSegment
                  : rule == "fixed_step" ? StepRule::kFixedStep
                                         : StepRule::kDiagonalOverN;
    s.step = sm->get_in_range<double>("step", 0.0, 0.0, 1e300);
    if (s.step_rule != StepRule::kDiagonalOverN && !(s.step > 0)) sm->fail("ds_rule " + rule + " needs 'step' > 0");
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
  // --- seed 001's transfer function ---
  if (const auto t = c.optional_section("transfer_function")) {
    if (s.model != OpticalModel::kTransferFunction) t->fail("'transfer_function' is for model: transfer_function");
    parse_transfer_function(*t, scene);
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
    s.ess = a->get_choice("ess", "multi_level", {"multi_level", "one_level"}) == "one_level"
                ? EmptySpaceScheme::kOneLevel
                : EmptySpaceScheme::kMultiLevel;
    s.ess_test = a->get_choice("ess_test", "range", {"range", "voxel"}) == "voxel" ? EmptyCellTest::kVoxel
                                                                                   : EmptyCellTest::kRange;
  }
  if (const auto t = c.optional_section("traversal")) {
    s.traversal = t->get_choice("method", "image_order", {"image_order", "object_order"}) == "object_order"
                      ? Traversal::kObjectOrder
                      : Traversal::kImageOrder;
    s.tile = t->get_in_range<int>("tile", 10, 1, 4096);
    s.render_threads = t->get_in_range<int>("render_threads", 0, 0, 1024);
    s.restrict_canvas = t->get<bool>("restrict_canvas", true);
    s.parallel = t->get<bool>("parallel", true);
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
  if (scene.slicing) {
    scene.slicing->settings.background = s.background;
    if (scene.mode == VolumeOutputMode::kComposite) c.fail_at("output", "method: slicing renders standalone frames");
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
  const SceneVolume v = load_scene_volumes(scene);
  if (v.is_bricked())
    throw InputError(fmt::format("{}: the volume is in blocks; this renderer reads linear volumes (layout: linear)",
                                 scene.volume.file.string()));
  return v.dense;
}

SceneVolume load_scene_volumes(const VolumeScene& scene) {
  SceneVolume out;
  const VolumeSource& src = scene.volume;
  if (src.generate) {
    out.dense = generate_volume(*src.generate);
  } else if (src.file.extension() == ".clv") {
    ClvVolume c = open_clv(src.file, src.memory, src.samples);
    out.clv = c.header;
    if (c.blocked())
      out.bricked = c.bricked;
    else
      out.dense = c.linear;
  } else {
    VolumeReadInfo info;
    out.dense = read_volume(src.file, src.read, &info);
    out.normalisation = info.normalisation;
  }
  // The layout asked for (converted in memory).
  if (src.layout == VolumeLayout::kBlocked && !out.is_bricked()) {
    if (out.dense.nx() < 2 || out.dense.ny() < 2 || out.dense.nz() < 2)
      throw InputError("volume.layout: blocked needs at least 2 samples per axis");
    out.bricked = BrickedVolume::from_volume(out.dense, src.block_side);
    out.dense = Volume();
  } else if (src.layout == VolumeLayout::kLinear && out.is_bricked()) {
    out.dense = out.bricked.to_volume();
    out.bricked = BrickedVolume();
  }
  if (src.samples == ClvSamples::kFloat32 && !out.clv) {  // .clv files convert at load
    if (out.is_bricked())
      out.bricked = out.bricked.to_float32();
    else if (out.dense.type() != SampleType::kFloat32)
      out.dense = out.dense.to_float32();
  }
  if (src.box) {
    if (out.is_bricked())
      out.bricked.fit_to_box(*src.box);
    else
      out.dense.fit_to_box(*src.box);
  }
  return out;
}

std::vector<std::pair<std::string, std::string>> describe_clv(const VolumeScene& scene, const SceneVolume& volume) {
  const VolumeRenderSettings& s = scene.settings;
  std::vector<std::pair<std::string, std::string>> r;
  auto add = [&](const std::string& k, const std::string& v) { r.emplace_back("clv." + k, v); };
  auto num = [](double x) { return fmt::format("{:.17g}", x); };
  const auto dims = volume.is_bricked() ? volume.bricked.dims() : volume.dense.dims();
  add("volume.dims", fmt::format("{} x {} x {}", dims[0], dims[1], dims[2]));
  add("layout.linear_order", volume.is_bricked() ? "blocks" : "z fastest (i = z + y N_z + x N_y N_z) in .clv files");
  add("layout.block_side", volume.is_bricked() ? std::to_string(volume.bricked.side()) : "-");
  add("layout.block_overlap", "1");
  add("layout.block_pad_value", "0");
  add("header.int_type", "uint32 LE");
  if (volume.clv)
    add("cell_shape.apply", fmt::format("ignored (the file's: {}, {}, {})", volume.clv->cell_shape[0],
                                        volume.clv->cell_shape[1], volume.clv->cell_shape[2]));
  add("memory",
      scene.volume.file.extension() == ".clv" ? (scene.volume.memory == ClvMemory::kMmap ? "mmap" : "ram") : "ram");
  add("samples", sample_type_name(volume.is_bricked() ? volume.bricked.type() : volume.dense.type()));
  add("tf.table", s.tf.table.name());
  for (const auto& t : s.tf.table.ranges())
    add("tf.range" + t.bounds_text(),
        fmt::format("rgb ({}, {}, {}) alpha {}", t.rgb.x(), t.rgb.y(), t.rgb.z(), t.alpha));
  add("tf.classification", "post");
  add("tf.opacity_exponent", opacity_exponent_name(s.tf.exponent));
  add("tf.reference_step", s.tf.reference_step > 0 ? num(s.tf.reference_step) : "1 voxel");
  add("gradient.scheme", s.tf.shading.gradient == GradientScheme::kCentral ? "central, n = 1" : "one_sided (repo)");
  add("gradient.boundary", "clamp");
  add("shade.enabled", s.tf.shading.enabled ? "true" : "false");
  add("shade.grad_threshold", num(s.tf.shading.threshold));
  add("shade.light_dir", fmt::format("[{}, {}, {}]", num(s.tf.shading.light_dir.x()), num(s.tf.shading.light_dir.y()),
                                     num(s.tf.shading.light_dir.z())));
  add("shade.ka", num(s.tf.shading.ka));
  add("shade.q", num(s.tf.shading.q));
  add("shade.ks", num(s.tf.shading.ks));
  add("sampling.step", s.step_rule == StepRule::kDiagonalOverN ? fmt::format("diagonal / {}", s.samples) : num(s.step));
  add("sampling.alignment", s.first_offset == FirstOffset::kZero   ? "entry"
                            : s.first_offset == FirstOffset::kHalf ? "entry + step/2"
                                                                   : "jitter");
  add("camera.pixel_offset", "0.5 (centre)");
  add("output.final_multiply", scene.tf_output == TfOutput::kSourceDouble ? "source_double (C A)" : "premultiplied");
  add("ert.threshold", s.ert_transmittance > 0 ? num(1 - s.ert_transmittance) : "off");
  add("ess", s.skip_empty ? ess_scheme_name(s.ess) : "off");
  add("ess.cell", "4");
  add("ess.index_test", s.ess_test == EmptyCellTest::kRange ? "range (exact)" : "voxel (repo)");
  add("ess.skip_mode", s.ess == EmptySpaceScheme::kOneLevel ? "one_step" : "to_region_exit (verified)");
  add("traversal", traversal_name(s.traversal));
  add("par.tile", std::to_string(s.tile));
  add("par.render_threads", s.render_threads > 0 ? std::to_string(s.render_threads) : "hardware threads");
  add("par.compositor_threads", "1 (a serial flow-graph node)");
  add("par.sort_key", "centre distance");
  add("par.sample_grid", "global (t0 + k s per ray)");
  add("par.block_entry_test", "projected rectangle, then the block's own samples per ray");
  add("canvas.restrict", s.restrict_canvas ? "true" : "false");
  if (src_is_shapes(scene)) {
    const auto& g = scene.volume.generate->shapes;
    add("gen.rng", "xoshiro256** (splitmix64 seeding)");
    add("gen.seed", std::to_string(g.seed));
    add("gen.shapes", std::to_string(g.count));
    add("gen.sample", std::to_string(g.sample));
    add("gen.object_size", std::to_string(g.object_size));
  }
  add("timing.protocol", fmt::format("{} warm-up frames, median of {}", scene.warmup_frames, scene.timed_frames));
  return r;
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
