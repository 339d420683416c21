#include <meltlab/core/error.h>
#include <meltlab/sim/kl_field.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <random>

#include "test_files.h"

namespace meltlab::sim {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using V3 = Vec3<double>;

constexpr double kExact = 1e-12;

KlFieldPtr parse(const std::string& yaml, const KlContext& ctx = {}) {
  return parse_kl_field(YAML::Load(yaml), "test.yaml", ctx);
}
std::string parse_error(const std::string& yaml, const KlContext& ctx = {}) {
  try {
    parse(yaml, ctx);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(KlField, ConstantIsConstant) {
  const auto f = parse("0.7");
  EXPECT_TRUE(f->is_constant());
  EXPECT_DOUBLE_EQ(f->value(V3(1, 2, 3)), 0.7);
  EXPECT_TRUE(parse("{type: constant, value: 0.25}")->is_constant());
}

TEST(KlField, PointSourceFalloffs) {
  const V3 c(0.1, 0.2, 0.3);
  struct Case {
    const char* name;
    double at_one_radius;
  } cases[] = {{"gaussian", std::exp(-0.5)}, {"inverse_square", 0.5}, {"linear", 0.0}, {"exponential", std::exp(-1.0)}};
  for (const auto& k : cases) {
    const auto f =
        parse(std::string(
                  "{type: point_source, position: [0.1, 0.2, 0.3], base: 0.2, strength: 0.6, radius: 0.05, falloff: ") +
              k.name + "}");
    EXPECT_FALSE(f->is_constant());
    EXPECT_NEAR(f->value(c), 0.8, kExact) << k.name;
    EXPECT_NEAR(f->value(c + V3(0, 0.05, 0)), 0.2 + 0.6 * k.at_one_radius, kExact) << k.name;
    EXPECT_NEAR(f->value(c + V3(100, 0, 0)), 0.2, 1e-6) << k.name << ": far from the source kl -> base";
    // Monotonically decreasing with distance.
    double prev = 2.0;
    for (double d = 0; d < 0.2; d += 0.01) {
      const double v = f->value(c + V3(d, 0, 0));
      EXPECT_LE(v, prev + kExact);
      prev = v;
    }
  }
}

TEST(KlField, GroundPressureIsStrongestAtTheGround) {
  KlContext ctx;
  ctx.bbox_min = V3(-1, -1, 0.5);
  ctx.bbox_max = V3(1, 1, 2.0);
  const auto f = parse("{type: ground, up: [0, 0, 1], height: auto, base: 0.3, strength: 0.7, height_scale: 0.1}", ctx);
  EXPECT_NEAR(f->value(V3(0, 0, 0.5)), 1.0, kExact) << "auto height = lowest point of the mesh";
  EXPECT_NEAR(f->value(V3(5, -3, 0.6)), 0.3 + 0.7 * std::exp(-1.0), kExact);
  EXPECT_NEAR(f->value(V3(0, 0, 0.0)), 1.0, kExact) << "below the ground: h clamps to 0";
  const auto g = parse("{type: ground, up: [0, 0, -2], height: -3, strength: 1, height_scale: 1}");
  EXPECT_NEAR(g->value(V3(0, 0, 2)), std::exp(-1.0), kExact) << "up is normalised; h = up·p - height";
}

TEST(KlField, CombinationsProductMaxMin) {
  const std::string a = "{type: point_source, position: [0,0,0], base: 0.1, strength: 0.9, radius: 1, falloff: linear}";
  const std::string b = "{type: constant, value: 0.5}";
  const V3 p(0.5, 0, 0);  // a = 0.1 + 0.9 * 0.5 = 0.55
  EXPECT_NEAR(parse("{type: product, of: [" + a + ", " + b + "]}")->value(p), 0.275, kExact);
  EXPECT_NEAR(parse("{type: max, of: [" + a + ", " + b + "]}")->value(p), 0.55, kExact);
  EXPECT_NEAR(parse("{type: min, of: [" + a + ", " + b + "]}")->value(p), 0.5, kExact);
  EXPECT_TRUE(parse("{type: product, of: [0.5, 0.5]}")->is_constant());
}

TEST(KlField, BadConfigsNameTheProblem) {
  EXPECT_THAT(parse_error("{type: constant, value: 1.5}"), HasSubstr("[0, 1]"));
  EXPECT_THAT(parse_error("{type: constant, value: 0.5, colour: red}"), HasSubstr("unknown key 'colour'"));
  EXPECT_THAT(parse_error("{type: warm_air}"), HasSubstr("unknown kl field type 'warm_air'"));
  EXPECT_THAT(parse_error("{type: point_source, position: [0,0], radius: 1}"), HasSubstr("list of 3 numbers"));
  EXPECT_THAT(parse_error("{type: point_source, position: [0,0,0], radius: -1}"), HasSubstr("radius"));
  EXPECT_THAT(parse_error("{type: point_source, position: [0,0,0], radius: 1, base: 0.5, strength: 0.8}"),
              HasSubstr("exceeds 1"));
  EXPECT_THAT(parse_error("{type: ground, height_scale: abc}"), HasSubstr("must be a number"));
  EXPECT_THAT(parse_error("{type: product, of: []}"), HasSubstr("non-empty"));
  EXPECT_THAT(parse_error(".nan"), HasSubstr("finite"));
  EXPECT_THAT(parse_error("warm"), HasSubstr("must be a number"));
}

class KlGridFile : public ::testing::Test {
 protected:
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  std::string grid_error(const std::string& text) {
    try {
      read_kl_grid(write("bad.klgrid", text));
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  }
  test::TempFolder folder_;
  const fs::path dir_ = folder_.path();
};

// Trilinear interpolation reproduces any function that is linear in x, y and z exactly.
TEST_F(KlGridFile, TrilinearIsExactForLinearFields) {
  auto lin = [](const V3& p) { return 0.1 + 0.2 * p.x() + 0.15 * p.y() + 0.05 * p.z(); };
  std::string text = "meltlab-kl-grid 1\n# a linear field\ndims 3 4 2\norigin 0 0 0\nspacing 0.5 1 2\nvalues\n";
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 3; ++i) text += std::to_string(lin(V3(0.5 * i, 1.0 * j, 2.0 * k))) + " ";
  write("lin.klgrid", text);
  write("field.yaml", "kl: {type: grid, file: lin.klgrid}\n");
  const auto f = load_kl_field(dir_ / "field.yaml", {});
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int n = 0; n < 100; ++n) {
    const V3 p(u(rng), 3 * u(rng), 2 * u(rng));
    EXPECT_NEAR(f->value(p), lin(p), 1e-6) << "grid values are written with 6 decimals";
  }
  // Outside: clamp to the nearest edge sample.
  EXPECT_NEAR(f->value(V3(-5, 0, 0)), lin(V3(0, 0, 0)), 1e-6);
  write("field2.yaml", "kl: {type: grid, file: lin.klgrid, outside: 0.9}\n");
  EXPECT_DOUBLE_EQ(load_kl_field(dir_ / "field2.yaml", {})->value(V3(-5, 0, 0)), 0.9);
}

TEST_F(KlGridFile, BadGridFilesNameTheLine) {
  EXPECT_THAT(grid_error("hello\n"), HasSubstr("bad.klgrid:1"));
  EXPECT_THAT(grid_error("meltlab-kl-grid 1\ndims 2 2\n"), HasSubstr("bad.klgrid:2"));
  EXPECT_THAT(grid_error("meltlab-kl-grid 1\ndims 1 1 2\norigin 0 0 0\nspacing 1 1 1\nvalues\n0.5 1.5\n"),
              HasSubstr("bad.klgrid:6: value 1.5 outside [0, 1]"));
  EXPECT_THAT(grid_error("meltlab-kl-grid 1\ndims 1 1 2\norigin 0 0 0\nspacing 1 1 1\nvalues\n0.5\n"),
              HasSubstr("expected 2 values"));
  EXPECT_THAT(grid_error("meltlab-kl-grid 1\ndims 1 1 1\norigin 0 0 0\nspacing 1 0 1\nvalues\n0.5\n"),
              HasSubstr("spacing"));
}

TEST_F(KlGridFile, BadYamlFileIsRefused) {
  write("broken.yaml", "kl: {type: constant, value: [\n");
  EXPECT_THROW(load_kl_field(dir_ / "broken.yaml", {}), InputError);
  write("nokl.yaml", "something: 1\n");
  try {
    load_kl_field(dir_ / "nokl.yaml", {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("nokl.yaml"));
  }
  EXPECT_THROW(load_kl_field(dir_ / "missing.yaml", {}), InputError);
}

}  // namespace
}  // namespace meltlab::sim
