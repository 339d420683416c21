// load_observations: YAML and JSON manifests, globbing, and one test per kind of mistake
// (every message names the manifest, the line and the key).

#include <meltlab/render/camera.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/observations.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>
#include <vector>

#include "test_util.h"

namespace meltlab::verify {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const char* const kYaml =
    "meltlab_observations: 1\n"                                                                   // 1
    "object: giraffe\n"                                                                           // 2
    "frames:\n"                                                                                   // 3
    "  - {image: frames/0001.png, time_s: 0}\n"                                                   // 4
    "  - {image: frames/0002.png}\n"                                                              // 5
    "  - image: frames/0003.png\n"                                                                // 6
    "    time_s: 95\n"                                                                            // 7
    "interval_s: 40\n"                                                                            // 8
    "first_time_s: 10\n"                                                                          // 9
    "camera: {type: orthographic, width: 64, height: 48, pixels_per_mm: 10, centre_m: [0, 0]}\n"  // 10
    "roi: [4, 6, 50, 30]\n"                                                                       // 11
    "segmentation:\n"                                                                             // 12
    "  method: background\n"                                                                      // 13
    "  background: bg.png\n"                                                                      // 14
    "  channel: gray\n"                                                                           // 15
    "  blur_sigma_px: 1.5\n"                                                                      // 16
    "  object_darker: true\n"                                                                     // 17
    "  adaptive_block_px: 51\n"                                                                   // 18
    "ground_truth: ../truth/giraffe.json\n"                                                       // 19
    "mass_series: mass.csv\n";                                                                    // 20

// The same in JSON, written the way JSON tools write it (tabs, no space after ':').
const char* const kJson =
    "{\n"
    "\t\"meltlab_observations\":1,\n"
    "\t\"object\":\"giraffe\",\n"
    "\t\"frames\":[\n"
    "\t\t{\"image\":\"frames/0001.png\",\"time_s\":0},\n"
    "\t\t{\"image\":\"frames/0002.png\"},\n"
    "\t\t{\"image\":\"frames/0003.png\",\"time_s\":95.0}\n"
    "\t],\n"
    "\t\"interval_s\":40,\n"
    "\t\"first_time_s\":1e1,\n"
    "\t\"camera\":{\"type\":\"orthographic\",\"width\":64,\"height\":48,\"pixels_per_mm\":10,\"centre_m\":[0,0]},\n"
    "\t\"roi\":[4,6,50,30],\n"
    "\t\"segmentation\":{\"method\":\"background\",\"background\":\"bg.png\",\"channel\":\"gray\",\n"
    "\t\t\"blur_sigma_px\":1.5,\"object_darker\":true,\"adaptive_block_px\":51},\n"
    "\t\"ground_truth\":\"../truth/giraffe.json\",\n"
    "\t\"mass_series\":\"mass.csv\"\n"
    "}\n";

class Manifest : public ::testing::Test {
 protected:
  void SetUp() override {
    obs_ = dir_ / "obs";
    fs::create_directories(obs_ / "frames");
    fs::create_directories(obs_ / "g");
    const cv::Mat img(48, 64, CV_8UC3, cv::Scalar(20, 30, 40));
    for (const char* name : {"0001.png", "0002.png", "0003.png"}) write_image(obs_ / "frames" / name, img);
    write_image(obs_ / "bg.png", img);
    test::write_file(obs_ / "mass.csv", "time_s,mass_g\n0,1\n");
    test::write_file(dir_ / "truth" / "giraffe.json", "{}\n");
  }

  /// The base YAML with line `line` (1-based) replaced by `text` (which may hold several
  /// lines, or none).
  static std::string with_line(int line, const std::string& text) {
    std::istringstream in(kYaml);
    std::string out, l;
    for (int n = 1; std::getline(in, l); ++n) out += (n == line ? text : l + "\n");
    return out;
  }

  std::string error_of(const std::string& content, const std::string& name = "m.yaml") {
    const fs::path file = obs_ / name;
    test::write_file(file, content);
    try {
      load_observations(file);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }

  /// Expects an error at `line` of m.yaml naming `key`.
  void expect_error(const std::string& content, int line, const std::string& key) {
    const std::string msg = error_of(content);
    EXPECT_THAT(msg, HasSubstr((obs_ / "m.yaml").string() + ":" + std::to_string(line) + ": ")) << content;
    EXPECT_THAT(msg, HasSubstr(key)) << content;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }

  test::TempDir dir_;
  fs::path obs_;
};

TEST_F(Manifest, YamlReadsEverything) {
  test::write_file(obs_ / "m.yaml", kYaml);
  const ObservationSequence s = load_observations(obs_ / "m.yaml");
  EXPECT_EQ(s.manifest, (obs_ / "m.yaml").lexically_normal());
  EXPECT_EQ(s.object, "giraffe");
  ASSERT_EQ(s.frames.size(), 3U);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(s.frames[static_cast<std::size_t>(i)].index, i);
    EXPECT_EQ(s.frames[static_cast<std::size_t>(i)].image, obs_ / "frames" / ("000" + std::to_string(i + 1) + ".png"));
  }
  ASSERT_TRUE(s.frames[0].time_s && s.frames[1].time_s && s.frames[2].time_s);
  EXPECT_EQ(*s.frames[0].time_s, 0);
  EXPECT_EQ(*s.frames[1].time_s, 50);  // first_time_s + 1 * interval_s
  EXPECT_EQ(*s.frames[2].time_s, 95);
  EXPECT_EQ(s.interval_s, 40);
  EXPECT_EQ(render::camera_width(s.camera), 64);
  EXPECT_EQ(render::camera_height(s.camera), 48);
  ASSERT_TRUE(std::holds_alternative<render::OrthographicTopDown>(s.camera));
  EXPECT_DOUBLE_EQ(std::get<render::OrthographicTopDown>(s.camera).pixels_per_unit, 10000);
  EXPECT_EQ(s.roi, cv::Rect(4, 6, 50, 30));
  EXPECT_EQ(s.segmentation.method, SegmentationSettings::Method::kBackground);
  EXPECT_EQ(s.segmentation.background, obs_ / "bg.png");
  EXPECT_EQ(s.segmentation.channel, "gray");
  EXPECT_EQ(s.segmentation.blur_sigma_px, 1.5);
  EXPECT_TRUE(s.segmentation.object_darker);
  EXPECT_EQ(s.segmentation.adaptive_block_px, 51);
  EXPECT_EQ(s.segmentation.open_radius_px, SegmentationSettings{}.open_radius_px);  // default kept
  EXPECT_EQ(s.ground_truth, dir_ / "truth" / "giraffe.json");
  EXPECT_EQ(s.mass_series, obs_ / "mass.csv");
}

TEST_F(Manifest, JsonLoadsLikeYaml) {
  test::write_file(obs_ / "m.yaml", kYaml);
  test::write_file(obs_ / "m.json", kJson);
  const ObservationSequence a = load_observations(obs_ / "m.yaml");
  const ObservationSequence b = load_observations(obs_ / "m.json");
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    EXPECT_EQ(a.frames[i].index, b.frames[i].index);
    EXPECT_EQ(a.frames[i].image, b.frames[i].image);
    EXPECT_EQ(a.frames[i].time_s, b.frames[i].time_s);
  }
  EXPECT_EQ(a.object, b.object);
  EXPECT_EQ(a.interval_s, b.interval_s);
  EXPECT_TRUE(a.camera == b.camera);
  EXPECT_EQ(a.roi, b.roi);
  EXPECT_EQ(a.segmentation.method, b.segmentation.method);
  EXPECT_EQ(a.segmentation.background, b.segmentation.background);
  EXPECT_EQ(a.segmentation.channel, b.segmentation.channel);
  EXPECT_EQ(a.segmentation.blur_sigma_px, b.segmentation.blur_sigma_px);
  EXPECT_EQ(a.segmentation.object_darker, b.segmentation.object_darker);
  EXPECT_EQ(a.segmentation.adaptive_block_px, b.segmentation.adaptive_block_px);
  EXPECT_EQ(a.ground_truth, b.ground_truth);
  EXPECT_EQ(a.mass_series, b.mass_series);
}

TEST_F(Manifest, JsonMistakesHaveLines) {
  std::string bad = kJson;
  bad.replace(bad.find("\"interval_s\""), 12, "\"interval\"");  // line 9
  std::string msg = error_of(bad, "m.json");
  EXPECT_THAT(msg, HasSubstr((obs_ / "m.json").string() + ":9: "));
  EXPECT_THAT(msg, HasSubstr("'interval'"));
  // A JSON syntax error (missing comma) is reported with its line too.
  bad = kJson;
  bad.replace(bad.find("\"giraffe\","), 10, "\"giraffe\"");  // line 3; the error shows on line 4
  msg = error_of(bad, "m.json");
  EXPECT_THAT(msg, HasSubstr((obs_ / "m.json").string() + ":4: "));
  EXPECT_THAT(msg, HasSubstr("JSON"));
}

TEST_F(Manifest, GlobSortsByNameAndTimesFromInterval) {
  // Names that sort differently as numbers and as text: sorted by name.
  const cv::Mat img(48, 64, CV_8UC1, cv::Scalar(0));
  write_image(obs_ / "g" / "b10.png", img);
  write_image(obs_ / "g" / "b02.png", img);
  write_image(obs_ / "g" / "a.png", img);
  write_image(obs_ / "g" / "skip.jpg", img);
  test::write_file(obs_ / "m.yaml",
                   "meltlab_observations: 1\n"
                   "frames: {glob: \"g/*.png\"}\n"
                   "interval_s: 30\n"
                   "first_time_s: 5\n"
                   "camera: {type: orthographic, width: 64, height: 48, pixels_per_unit: 100, centre: [0, 0]}\n");
  const ObservationSequence s = load_observations(obs_ / "m.yaml");
  ASSERT_EQ(s.frames.size(), 3U);
  EXPECT_EQ(s.frames[0].image, obs_ / "g" / "a.png");
  EXPECT_EQ(s.frames[1].image, obs_ / "g" / "b02.png");
  EXPECT_EQ(s.frames[2].image, obs_ / "g" / "b10.png");
  EXPECT_EQ(s.frames[0].time_s, 5);
  EXPECT_EQ(s.frames[2].time_s, 65);
  EXPECT_FALSE(s.roi);
  EXPECT_EQ(s.segmentation.method, SegmentationSettings::Method::kOtsu);
  EXPECT_FALSE(s.ground_truth);
}

TEST_F(Manifest, NoTimesWithoutIntervalOrTimes) {
  test::write_file(obs_ / "m.yaml",
                   "meltlab_observations: 1\n"
                   "frames: [frames/0001.png, frames/0002.png]\n"
                   "camera: {type: orthographic, width: 64, height: 48, pixels_per_mm: 1}\n");
  const ObservationSequence s = load_observations(obs_ / "m.yaml");
  ASSERT_EQ(s.frames.size(), 2U);
  EXPECT_FALSE(s.frames[0].time_s);
  EXPECT_FALSE(s.interval_s);
}

TEST_F(Manifest, AMissingFrameIsNotAnError) {
  test::write_file(obs_ / "m.yaml", with_line(5, "  - {image: frames/0009.png}\n"));
  const ObservationSequence s = load_observations(obs_ / "m.yaml");
  ASSERT_EQ(s.frames.size(), 3U);
  EXPECT_EQ(s.frames[1].image, obs_ / "frames" / "0009.png");
  EXPECT_FALSE(fs::exists(s.frames[1].image));
}

TEST_F(Manifest, NoExistingFrameIsAnError) {
  test::write_file(obs_ / "m.yaml",
                   "meltlab_observations: 1\n"
                   "camera: {type: orthographic, width: 64, height: 48, pixels_per_mm: 1}\n"
                   "frames:\n"
                   "  - frames/x1.png\n"
                   "  - frames/x2.png\n");
  try {
    load_observations(obs_ / "m.yaml");
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr((obs_ / "m.yaml").string() + ":4: "));
    EXPECT_THAT(e.what(), HasSubstr("frames"));
  }
}

TEST_F(Manifest, EveryMistakeNamesFileLineAndKey) {
  struct Case {
    int line;
    std::string text;
    int error_line;
    std::string key;
  };
  const std::vector<Case> cases = {
      {20, "mass_series: mass.csv\ncolour: red\n", 21, "colour"},       // unknown key
      {8, "interval_s: -5\n", 8, "interval_s"},                         // negative interval
      {8, "interval_s: soon\n", 8, "interval_s"},                       // wrong type
      {9, "first_time_s: [1]\n", 9, "first_time_s"},                    // wrong type
      {11, "roi: [40, 6, 50, 30]\n", 11, "roi"},                        // outside the 64x48 image
      {11, "roi: [4, 6, wide, 30]\n", 11, "roi"},                       // wrong type
      {11, "roi: [4, 6, 50]\n", 11, "roi"},                             // wrong length
      {5, "  - {image: frames/0001.png}\n", 5, "twice"},                // duplicated frame
      {5, "  - {image: frames/0002.png, time: 3}\n", 5, "time"},        // unknown frame key
      {5, "  - {time_s: 3}\n", 5, "image"},                             // frame without image
      {7, "    time_s: 30\n", 6, "time_s"},                             // not after frame 1 (50 s)
      {13, "  method: magic\n", 13, "method"},                          // unknown method
      {15, "  channel: hue\n", 15, "channel"},                          // unknown channel
      {18, "  adaptive_block_px: 50\n", 18, "adaptive_block_px"},       // even block
      {16, "  blur_radius: 2\n", 16, "blur_radius"},                    // unknown segmentation key
      {17, "  object_darker: maybe\n", 17, "object_darker"},            // not a boolean
      {14, "  background: nothing.png\n", 14, "background"},            // missing background
      {1, "meltlab_observations: 2\n", 1, "meltlab_observations"},      // version
      {19, "ground_truth: ../truth/zebra.json\n", 19, "ground_truth"},  // missing file
      {10, "camera: {type: orthographic, width: 64, height: 48, pixels_per_mm: 10, zoom: 2}\n", 10, "zoom"},
      {10, "camera: {type: orthographic, width: 65, height: 48, pixels_per_mm: 10}\n", 10, "camera"},  // size
      {10, "", 1, "camera"},                                                                           // missing camera
      {3, "frames: {glob: \"frames/*.tif\"}\n", 3, "glob"},  // glob matching nothing
      {2, "object: {name: giraffe}\n", 2, "object"},         // wrong type
  };
  for (const Case& c : cases) {
    std::string content = with_line(c.line, c.text);
    if (c.key == "glob") {
      // Drop the list items of the explicit frames (lines 4-7).
      std::istringstream in(content);
      std::string l, out;
      for (int n = 1; std::getline(in, l); ++n)
        if (n < 4 || n > 7) out += l + "\n";
      content = out;
    }
    SCOPED_TRACE(c.text);
    expect_error(content, c.error_line, c.key);
  }
}

TEST_F(Manifest, AMassSeriesAloneIsAWeighingExperiment) {
  test::write_file(obs_ / "w.yaml", "meltlab_observations: 1\nobject: cube\nmass_series: mass.csv\n");
  const ObservationSequence w = load_observations(obs_ / "w.yaml");
  EXPECT_FALSE(w.has_photos());
  EXPECT_TRUE(w.frames.empty());
  ASSERT_TRUE(w.mass_series.has_value());
  EXPECT_EQ(w.mass_series->filename(), "mass.csv");
  EXPECT_EQ(w.object, "cube");
  // volume_series is the same key, for a file of volumes.
  test::write_file(obs_ / "v.yaml", "meltlab_observations: 1\nvolume_series: mass.csv\n");
  EXPECT_EQ(load_observations(obs_ / "v.yaml").mass_series->filename(), "mass.csv");
  // A photo manifest keeps its photos.
  test::write_file(obs_ / "m.yaml", kYaml);
  EXPECT_TRUE(load_observations(obs_ / "m.yaml").has_photos());

  // Neither frames nor a series; keys only photos need; both series keys.
  expect_error("meltlab_observations: 1\nobject: cube\n", 1, "frames");
  expect_error("meltlab_observations: 1\nmass_series: mass.csv\ncamera: {type: orthographic}\n", 3, "camera");
  expect_error("meltlab_observations: 1\nmass_series: mass.csv\nroi: [0, 0, 4, 4]\n", 3, "roi");
  expect_error("meltlab_observations: 1\nmass_series: mass.csv\nsegmentation: {channel: gray}\n", 3, "segmentation");
  expect_error("meltlab_observations: 1\nmass_series: mass.csv\nvolume_series: mass.csv\n", 3, "volume_series");
  expect_error("meltlab_observations: 1\nmass_series: nope.csv\n", 2, "nope.csv");
}

TEST_F(Manifest, BrokenFiles) {
  EXPECT_THAT(error_of("meltlab_observations: 1\nframes: [a.png\n"), HasSubstr("m.yaml:"));
  EXPECT_THAT(error_of(""), HasSubstr("empty"));
  EXPECT_THAT(error_of("- just\n- a list\n"), HasSubstr("mapping"));
  EXPECT_THAT(error_of(kYaml, "m.txt"), HasSubstr(".yaml"));
  try {
    load_observations(obs_ / "none.yaml");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("none.yaml: no such file"));
  }
}

}  // namespace
}  // namespace meltlab::verify
