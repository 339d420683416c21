// The `slicing:` section of a volume scene (see slicing/slicing_scene.h).

#include <meltlab/render/slicing/slicing_scene.h>

#include <meltlab/core/config.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

namespace meltlab::render {

namespace {

TfCurve curve_of(const ConfigValue& v) {
  TfCurve c;
  for (const ConfigValue& item : v.items()) {
    const auto p = item.as_numbers(2, 2);
    c.points.emplace_back(p[0], p[1]);
  }
  return c;
}

TransferFunction parse_tf(const ConfigSection& t, int index) {
  std::array<TfCurve, 4> curves;
  const std::string name = t.get<std::string>("name", fmt::format("tf{}", index + 1));
  if (t.has("points")) {
    for (const char* ch : {"r", "g", "b", "a"})
      if (t.has(ch)) t.fail_at(ch, "give 'points' or per-channel curves (r, g, b, a), not both");
    for (const ConfigValue& row : t.value("points").items()) {
      const auto p = row.as_numbers(5, 5);
      for (int c = 0; c < 4; ++c) curves[std::size_t(c)].points.emplace_back(p[0], p[std::size_t(c) + 1]);
    }
  } else {
    const char* ch[4] = {"r", "g", "b", "a"};
    for (int c = 0; c < 4; ++c)
      if (const auto v = t.optional_value(ch[c])) curves[std::size_t(c)] = curve_of(*v);
    if (!t.has("a")) t.fail("a transfer function needs 'points' (rows v, r, g, b, a) or an 'a' curve");
  }
  try {
    return TransferFunction::piecewise_linear(curves, name, fmt::format("transfer function {}", index + 1));
  } catch (const InputError& e) {
    t.fail(e.what());
  }
  return {};
}

MaskEdit parse_edit(const ConfigSection& e) {
  MaskEdit m;
  const std::string shape = e.require<std::string>("shape");
  if (shape == "box") {
    m.shape = MaskShape::kBox;
    m.half_size = 0.5 * e.require_vec3("size");
  } else if (shape == "sphere") {
    m.shape = MaskShape::kSphere;
    m.half_size = Eigen::Vector3d::Constant(e.require_in_range<double>("radius", 1e-9, 1e6));
  } else if (shape == "ellipsoid") {
    m.shape = MaskShape::kEllipsoid;
    m.half_size = e.require_vec3("radii");
  } else {
    e.fail_at("shape", fmt::format("unknown mask shape '{}' (box, sphere, ellipsoid)", shape));
  }
  if (!(m.half_size.minCoeff() > 0) || !m.half_size.allFinite()) e.fail("a mask object's sizes must be > 0");
  m.centre = e.require_vec3("centre");
  if (m.shape != MaskShape::kSphere) m.rotate_deg = e.get_vec3("rotate_deg", Eigen::Vector3d::Zero());
  m.index = e.require_in_range<int>("index", 0, 4);
  return m;
}

}  // namespace

SlicingScene parse_slicing_scene(const ConfigSection& c) {
  SlicingScene out;
  SlicingSettings& s = out.settings;
  const std::string mode = c.get_choice("mode", "blend", {"blend", "mip", "combined"});
  s.mode = mode == "mip" ? SlicingMode::kMip : mode == "combined" ? SlicingMode::kCombined : SlicingMode::kBlend;
  s.quality_class = c.get_in_range<double>("quality_class", 1.0, 0.01, 1000.0);
  s.d_range = c.get_choice("d_range", "tight", {"tight", "conservative"}) == "conservative" ? SliceRange::kConservative
                                                                                            : SliceRange::kTight;
  s.blend = c.get_choice("blend_operator", "over", {"over", "additive"}) == "additive" ? BlendOperator::kAdditive
                                                                                       : BlendOperator::kOver;
  s.opacity_correction = c.get<bool>("opacity_correction", true);
  s.lit_blend = c.get<bool>("lit_blend", false);
  if (c.has("value_range")) {
    const auto r = c.require_numbers("value_range", 2, 2);
    if (!(r[1] > r[0])) c.fail_at("value_range", "'value_range' needs [lo, hi] with hi > lo");
    s.value_range = std::make_pair(r[0], r[1]);
  }
  if (const auto g = c.optional_section("gradient")) {
    s.gradient.radius = g->get_in_range<int>("radius", 2, 1, 4);
    s.gradient.neighbourhood = g->get_choice("neighbourhood", "cube", {"cube", "ball"}) == "ball"
                                   ? GradientNeighbourhood::kBall
                                   : GradientNeighbourhood::kCube;
    s.gradient.bits = std::stoi(g->get_choice("bits", "8", {"8", "4"}));
    out.cache_gradients = g->get<bool>("cache", true);
  }
  if (const auto l = c.optional_section("light")) {
    s.light.light_camera = l->get_vec3("position_camera", Eigen::Vector3d::Ones());
    s.light.ambient = l->get_in_range<double>("ambient", 0.2, 0.0, 1e6);
    s.light.diffuse = l->get_in_range<double>("diffuse", 0.7, 0.0, 1e6);
    s.light.specular = l->get_in_range<double>("specular", 0.3, 0.0, 1e6);
    s.light.exponent = l->get_in_range<double>("exponent", 32.0, 0.0, 1e6);
    s.light.gate = l->get_in_range<double>("gate", 0.0, 0.0, 2.0);
  }
  if (const auto m = c.optional_section("mask")) {
    out.mask = true;
    if (m->has("resolution")) {
      const auto r = m->require_numbers("resolution", 3, 3);
      for (int a = 0; a < 3; ++a) {
        const double x = r[std::size_t(a)];
        if (!(x >= 1 && x <= 1024 && x == std::floor(x)))
          m->fail_at("resolution", "'resolution' must be three whole numbers in [1, 1024]");
        out.mask_resolution[std::size_t(a)] = int(x);
      }
    }
    if (m->has("edits"))
      for (const ConfigSection& e : m->sections("edits")) out.mask_edits.push_back(parse_edit(e));
  }
  if (c.has("transfer_functions")) {
    const auto items = c.value("transfer_functions").items();
    if (items.empty() || items.size() > 4) c.fail_at("transfer_functions", "give 1 to 4 transfer functions");
    for (std::size_t i = 0; i < items.size(); ++i) s.tfs[i] = parse_tf(items[i].section(), int(i));
  } else {
    c.fail("'slicing' needs 'transfer_functions' (1 to 4 piecewise-linear TFs)");
  }
  if (const auto b = c.optional_section("bloom")) {
    s.post.enabled = b->get<bool>("enabled", false);
    s.post.adjust.contrast = b->get_in_range<double>("contrast", 1.0, 0.0, 1e3);
    s.post.adjust.brightness = b->get_in_range<double>("brightness", 0.0, -1.0, 1.0);
    s.post.adjust.gamma = b->get_in_range<double>("gamma", 1.0, 0.01, 100.0);
    s.post.threshold = b->get_in_range<double>("threshold", 0.7, 0.0, 1e6);
    s.post.sigma = b->get_in_range<double>("sigma", 2.0, 0.05, 64.0);
    s.post.gain = b->get_in_range<double>("gain", 1.0, 0.0, 1e6);
  }
  s.tile = c.get_in_range<int>("tile", 16, 1, 4096);
  s.parallel = c.get<bool>("parallel", true);
  s.skip_empty = c.get<bool>("skip_empty", true);
  s.skip_cell = c.get_in_range<int>("skip_cell", 4, 2, 16);
  if (s.skip_cell != 2 && s.skip_cell != 4 && s.skip_cell != 8 && s.skip_cell != 16)
    c.fail_at("skip_cell", "'skip_cell' must be 2, 4, 8 or 16");
  s.skip_voxels = c.get<bool>("skip_voxels", true);
  s.early_termination = c.get_in_range<double>("early_termination", 0.0, 0.0, 1.0);
  s.exact_positions = c.get<bool>("exact_positions", false);
  s.simd = c.get<bool>("simd", true);
  s.exact_pow = c.get<bool>("exact_pow", false);
  return out;
}

MaskVolume build_scene_mask(const SlicingScene& scene, const Box3& box) {
  if (!scene.mask) return {};
  MaskVolume m(scene.mask_resolution, box, 1);
  for (const MaskEdit& e : scene.mask_edits) m.apply(e);
  return m;
}

}  // namespace meltlab::render
