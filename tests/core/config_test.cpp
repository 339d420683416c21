// The YAML config reader (core/config.h) on hand-built documents: typed values with defaults,
// wrong types, missing / unknown / unused / duplicate keys, nested sections and lists of them,
// and the FILE:LINE of every error.

#include <meltlab/core/config.h>
#include <meltlab/core/error.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>

namespace meltlab {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

ConfigSection section_of(const std::string& yaml) { return ConfigSection(YAML::Load(yaml), "c.yaml"); }

/// The message of the InputError `f` throws ("no error" if none; another exception fails).
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    return msg;
  }
  return "no error";
}

TEST(Config, TypedValuesAndDefaults) {
  const ConfigSection c = section_of(
      "fov_deg: 30.5\n"
      "count: 7\n"
      "big: 12345678901\n"
      "on: yes\n"
      "name: bunny\n"
      "eye: [1, 2.5, -3]\n");
  EXPECT_EQ(c.get<double>("fov_deg", 45.0), 30.5);
  EXPECT_EQ(c.get<double>("near", 0.25), 0.25);  // absent: the default
  EXPECT_EQ(c.require<int>("count"), 7);
  EXPECT_EQ(c.require<std::int64_t>("big"), 12345678901);
  EXPECT_TRUE(c.require<bool>("on"));
  EXPECT_EQ(c.require<std::string>("name"), "bunny");
  EXPECT_EQ(c.optional<std::string>("title"), std::nullopt);
  EXPECT_EQ(c.require_vec3("eye"), Eigen::Vector3d(1, 2.5, -3));
  EXPECT_EQ(c.get_vec3("up", Eigen::Vector3d(0, 0, 1)), Eigen::Vector3d(0, 0, 1));
  EXPECT_NO_THROW(c.finish());
}

TEST(Config, WrongTypesNameFileLineAndKey) {
  const ConfigSection c = section_of(
      "a: 1\n"
      "n: abc\n"        // line 2
      "i: 1.5\n"        // line 3
      "b: maybe\n"      // line 4
      "s: [x]\n"        // line 5
      "v: [1, 2]\n"     // line 6
      "w: [1, x, 3]\n"  // line 7
      "f: .inf\n");     // line 8
  // yaml-cpp's BadConversion becomes an InputError naming the value.
  EXPECT_EQ(error_of([&] { c.require<double>("n"); }), "c.yaml:2: 'n' must be a number (got 'abc')");
  EXPECT_EQ(error_of([&] { c.require<int>("i"); }), "c.yaml:3: 'i' must be an integer (got '1.5')");
  EXPECT_EQ(error_of([&] { c.require<bool>("b"); }), "c.yaml:4: 'b' must be true or false (got 'maybe')");
  EXPECT_EQ(error_of([&] { c.require<std::string>("s"); }), "c.yaml:5: 's' must be a text value (got a list)");
  EXPECT_EQ(error_of([&] { c.require<double>("s"); }), "c.yaml:5: 's' must be a number (got a list)");
  EXPECT_EQ(error_of([&] { c.require_vec3("v"); }), "c.yaml:6: 'v' must be a list of 3 numbers (got a list)");
  EXPECT_EQ(error_of([&] { c.require_vec3("w"); }), "c.yaml:7: 'w[1]' must be a number (got 'x')");
  EXPECT_EQ(error_of([&] { c.require<double>("f"); }), "c.yaml:8: 'f' must be a finite number (got '.inf')");
}

TEST(Config, RangesAndChoices) {
  const ConfigSection c = section_of("eta: 5\nn: 0\nw: -2\nmode: exact\n");
  EXPECT_EQ(error_of([&] { c.get_in_range<double>("eta", 1.31, 1.0, 4.0); }),
            "c.yaml:1: 'eta' must be in [1, 4] (got 5)");
  EXPECT_EQ(c.get_in_range<double>("gamma", 2.2, 0.1, 10.0), 2.2);
  EXPECT_EQ(error_of([&] { c.require_in_range<int>("w", 1, 64); }), "c.yaml:3: 'w' must be in [1, 64] (got -2)");
  EXPECT_EQ(error_of([&] { c.require_positive("n"); }), "c.yaml:2: 'n' must be > 0 (got 0)");
  EXPECT_EQ(error_of([&] {
              c.get_choice("mode", "full", {"full", "schlick"});
            }),
            "c.yaml:4: 'mode' must be one of full, schlick (got 'exact')");
  EXPECT_EQ(c.get_choice("other", "full", {"full", "schlick"}), "full");
}

TEST(Config, NumberListsReadRows) {
  const ConfigSection c = section_of("m: [[1, 2], [3, 4]]\nd: [1, 2, 3]\n");
  EXPECT_EQ(c.require_numbers("m", 4, 4), (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(error_of([&] { c.require_numbers("d", 4, 5); }), "c.yaml:2: 'd' must have 4 to 5 numbers (got 3)");
  EXPECT_EQ(error_of([&] { c.require_numbers("m", 16, 16); }), "c.yaml:1: 'm' must have 16 numbers (got 4)");
}

TEST(Config, MissingKeyNamesTheMappingAndASpellingNearby) {
  const ConfigSection c = section_of("# a comment\nwidht: 64\nheight: 48\n");
  EXPECT_EQ(error_of([&] { c.require<int>("width"); }), "c.yaml:2: missing key 'width' (is 'widht' a typo?)");
  EXPECT_EQ(error_of([&] { c.require<int>("depth"); }), "c.yaml:2: missing key 'depth'");
}

TEST(Config, UnknownKeysAreRefusedAtTheirLine) {
  const ConfigSection c = section_of("width: 64\nheight: 48\ncolour: red\n");
  c.require<int>("width");
  c.require<int>("height");
  c.get<double>("depth", 1.0);
  EXPECT_EQ(error_of([&] { c.finish(); }), "c.yaml:3: unknown key 'colour' (allowed: depth, height, width)");
}

TEST(Config, KeysAskedForButNotReadAreRefused) {
  const ConfigSection c = section_of("fov: 40\nfx: 500\n");
  ASSERT_TRUE(c.has("fov"));  // known, but this variant reads fx only
  c.require<double>("fx");
  EXPECT_EQ(error_of([&] { c.finish(); }), "c.yaml:1: key 'fov' is not used here");
  c.ignore("fov");
  EXPECT_NO_THROW(c.finish());
}

TEST(Config, DuplicateAndNonNameKeysAreRefused) {
  EXPECT_EQ(error_of([] { section_of("a: 1\nb: 2\na: 3\n"); }), "c.yaml:3: key 'a' appears twice");
  EXPECT_EQ(error_of([] { section_of("a: 1\n[x]: 2\n"); }), "c.yaml:2: keys must be names");
  EXPECT_EQ(error_of([] { section_of("- a\n- b\n"); }), "c.yaml:1: must be a mapping of keys (got a list)");
  EXPECT_EQ(error_of([] { section_of(""); }), "c.yaml:1: must be a mapping of keys (got nothing)");
}

TEST(Config, NestedSectionsAreCheckedByTheRootsFinish) {
  const ConfigSection c = section_of(
      "camera:\n"
      "  type: pinhole\n"
      "  fx: 500\n"
      "  zoom: 2\n"  // line 4
      "lights:\n"
      "  - {to_light: [0, 0, 1]}\n"
      "  - {to_light: [1, 0, 1], colour: 3}\n"  // line 7
      "ice: {eta: 1.31}\n");
  const ConfigSection cam = c.section("camera");
  EXPECT_EQ(cam.path(), "camera");
  EXPECT_EQ(cam.line(), 2);
  EXPECT_EQ(cam.require<std::string>("type"), "pinhole");
  EXPECT_EQ(cam.require_positive("fx"), 500);
  const std::vector<ConfigSection> lights = c.sections("lights");
  ASSERT_EQ(lights.size(), 2U);
  for (const auto& l : lights) l.require_vec3("to_light");
  EXPECT_EQ(error_of([&] { lights[1].require_vec3("colour"); }),
            "c.yaml:7: 'lights[1].colour' must be a list of 3 numbers (got '3')");
  const auto ice = c.optional_section("ice");
  ASSERT_TRUE(ice);
  EXPECT_EQ(ice->get<double>("eta", 1.0), 1.31);
  EXPECT_FALSE(c.optional_section("ground"));
  // The root's finish() reaches the nested sections: zoom was never read.
  EXPECT_EQ(error_of([&] { c.finish(); }), "c.yaml:4: camera: unknown key 'zoom' (allowed: fx, type)");
  cam.ignore("zoom");
  EXPECT_NO_THROW(c.finish());  // (lights[1].colour was read, if badly)
  // A section that is not a mapping.
  EXPECT_EQ(error_of([&] { section_of("camera: 3\n").section("camera"); }),
            "c.yaml:1: camera: must be a mapping of keys (got '3')");
}

TEST(Config, FreeStandingValuesAndTheirSections) {
  // A value that may be a number or a mapping (a kl field), read outside any section.
  const ConfigValue scalar(YAML::Load("0.5"), "k.yaml", "kl");
  EXPECT_TRUE(scalar.is_scalar());
  EXPECT_EQ(scalar.as<double>(), 0.5);
  const ConfigValue field(YAML::Load("\n{type: product, of: [0.5, {type: constant, value: 1, extra: 2}]}"), "k.yaml",
                          "kl");
  ASSERT_TRUE(field.is_map());
  const ConfigSection top = field.section();
  EXPECT_EQ(top.require<std::string>("type"), "product");
  const std::vector<ConfigValue> of = top.value("of").items();
  ASSERT_EQ(of.size(), 2U);
  EXPECT_EQ(of[0].path(), "kl.of[0]");
  EXPECT_EQ(of[0].as<double>(), 0.5);
  const ConfigSection leaf = of[1].section();
  leaf.require<std::string>("type");
  leaf.require<double>("value");
  EXPECT_EQ(error_of([&] { field.finish(); }), "k.yaml:2: kl.of[1]: unknown key 'extra' (allowed: type, value)");
  EXPECT_EQ(error_of([&] { of[1].fail("not after the previous frame"); }),
            "k.yaml:2: kl.of[1]: not after the previous frame");
  EXPECT_EQ(error_of([&] { top.fail_at("type", "'type' product needs two fields"); }),
            "k.yaml:2: kl: 'type' product needs two fields");
}

TEST(Config, KeysInFileOrderForFreeFormMappings) {
  const ConfigSection c = section_of("params: {rings: 8, radius: 0.5, name: x}\n");
  const ConfigSection p = c.section("params");
  EXPECT_EQ(p.keys(), (std::vector<std::string>{"rings", "radius", "name"}));
  for (const auto& k : p.keys()) p.require<std::string>(k);
  EXPECT_NO_THROW(c.finish());
}

TEST(Config, LoadingAFileChecksSizeAndSyntax) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "meltlab_config_test";
  std::filesystem::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return dir / name;
  };
  const auto good = write("good.yaml", "name: x\nsize: 3\n");
  const ConfigSection c = load_config(good, "test config");
  EXPECT_EQ(c.file(), good.string());
  EXPECT_EQ(c.require<int>("size"), 3);
  EXPECT_EQ(error_of([&] { c.finish(); }), good.string() + ":1: unknown key 'name' (allowed: size)");

  const auto bad = write("bad.yaml", "name: x\nlist: [1, 2\n");
  EXPECT_THAT(error_of([&] { load_config(bad, "test config"); }), StartsWith(bad.string() + ":3: YAML syntax error: "));
  EXPECT_THAT(error_of([&] { load_config(dir / "none.yaml", "test config"); }),
              StartsWith((dir / "none.yaml").string() + ": no such file"));
  const auto empty = write("comments.yaml", "# nothing but a comment\n");
  EXPECT_EQ(error_of([&] { load_config(empty, "test config"); }),
            empty.string() + ":1: must be a mapping of keys (got nothing)");
  EXPECT_THAT(error_of([&] { parse_yaml_text("{\"a\": [1,}", "m.json", "JSON syntax error"); }),
              StartsWith("m.json:1: JSON syntax error: "));
}

}  // namespace
}  // namespace meltlab
