// Sequence comparison: frame mapping, overlays, skipped frames, and P of photos that are the
// renders themselves.

#include <meltlab/datasets/procedural.h>
#include <meltlab/render/raster/silhouette.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/compare.h>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "test_files.h"

namespace meltlab::verify {
namespace {

namespace fs = std::filesystem;

using TempDir = meltlab::test::TempFolder;

/// A sphere of radius r_k = r0 * (1 - 0.02 k) at cycle k; records the cycles asked for.
class ShrinkingSphere final : public sim::MeshSequence {
 public:
  const sim::TriMesh<double>& mesh_at(std::int64_t cycle) override {
    requested.push_back(cycle);
    const sim::IndexedMesh unit = datasets::geodesic_sphere(8);
    sim::IndexedMesh m = unit;
    const double r = 0.02 * (1.0 - 0.02 * static_cast<double>(cycle));
    for (auto& v : m.V) v = v.normalized() * r;
    mesh_ = sim::TriMesh<double>::from_indexed(m);
    return mesh_;
  }
  std::vector<std::int64_t> requested;

 private:
  sim::TriMesh<double> mesh_;
};

constexpr const char* kCamera = "{type: orthographic, width: 240, height: 180, pixels_per_unit: 2000, centre: [0, 0]}";

render::Camera camera() {
  render::OrthographicTopDown c;
  c.width = 240;
  c.height = 180;
  c.pixels_per_unit = 2000;
  return c;
}

/// Writes photos (white object on black) of the sphere at cycles 0, 5, 10, ... and a manifest.
fs::path write_sequence(const fs::path& dir, int frames, double cycles_per_photo) {
  ShrinkingSphere s;
  std::ostringstream manifest;
  manifest << "meltlab_observations: 1\nobject: sphere\ninterval_s: 40\ncamera: " << kCamera << "\nframes:\n";
  fs::create_directories(dir / "frames");
  for (int k = 0; k < frames; ++k) {
    const cv::Mat mask = render::silhouette_mask(s.mesh_at(std::llround(k * cycles_per_photo)), camera());
    const std::string name = fmt::format("f{}.png", k);
    write_image(dir / "frames" / name, mask);
    manifest << "  - frames/" << name << "\n";
  }
  std::ofstream(dir / "manifest.yaml") << manifest.str();
  return dir / "manifest.yaml";
}

TEST(FrameMapping, CyclesPerPhotoAndSecondsPerCycle) {
  Frame f;
  f.index = 3;
  f.time_s = 120;
  FrameMapping m;
  EXPECT_EQ(m.cycle_of(f, "x"), 21);  // default: 7 cycles per photo (§8.2)
  m.cycles_per_photo = 2.5;
  m.first_cycle = 4;
  EXPECT_EQ(m.cycle_of(f, "x"), 12);  // 4 + 7.5 rounded to nearest (ties away from zero)
  FrameMapping s;
  s.seconds_per_cycle = 6;
  EXPECT_EQ(s.cycle_of(f, "x"), 20);
  f.time_s.reset();
  EXPECT_THROW(s.cycle_of(f, "x"), InputError);
}

TEST(Overlay, UsesTheGreysOfFigure812) {
  cv::Mat a = cv::Mat::zeros(1, 4, CV_8UC1), b = cv::Mat::zeros(1, 4, CV_8UC1);
  a.at<std::uint8_t>(0, 0) = 255;                             // photo only
  b.at<std::uint8_t>(0, 1) = 255;                             // render only
  a.at<std::uint8_t>(0, 2) = b.at<std::uint8_t>(0, 2) = 255;  // common
  const cv::Mat o = overlay_image(a, b);
  EXPECT_EQ(o.at<std::uint8_t>(0, 0), 80);   // dark grey
  EXPECT_EQ(o.at<std::uint8_t>(0, 1), 0);    // black
  EXPECT_EQ(o.at<std::uint8_t>(0, 2), 192);  // light grey
  EXPECT_EQ(o.at<std::uint8_t>(0, 3), 255);  // background
}

TEST(CompareSequence, PhotosOfTheRendersGiveNearZeroP) {
  TempDir tmp;
  const fs::path manifest = write_sequence(tmp.path(), 6, 5);
  const ObservationSequence obs = load_observations(manifest);
  ShrinkingSphere meshes;
  CompareOptions o;
  o.mapping.cycles_per_photo = 5;
  o.registration = RegistrationMode::kNone;
  int calls = 0;
  const CompareResult r = compare_sequence(obs, meshes, o, [&](const FrameResult&, const FrameImages&) { ++calls; });
  EXPECT_EQ(calls, 6);
  EXPECT_EQ(r.compared, 6);
  for (const FrameResult& f : r.frames) {
    EXPECT_EQ(f.status, "ok");
    EXPECT_EQ(f.cycle, 5 * f.frame);
    // The photo is the render written as PNG and segmented again: blur + Otsu + morphology
    // can move a few boundary pixels of a ~80 px disc; P(1 ring of pixels) ~ 0.05.
    EXPECT_LT(f.pixels.P, 0.01) << f.frame;
    ASSERT_TRUE(f.P_exact.has_value());
    // The exact P compares the photo's outline (a binary image: a pixel staircase) with the
    // render's smooth one; a staircase strays up to half a pixel, so P <= perimeter * 0.5 px
    // / area = 1 / r_px for a disc of radius r_px.
    const double r_px = 40.0 * (1.0 - 0.02 * static_cast<double>(f.cycle));
    EXPECT_LT(*f.P_exact, 1.0 / r_px) << f.frame;
    EXPECT_LT(f.distances_px.hausdorff, 2.0) << f.frame;
    EXPECT_NEAR(f.mm_per_px, 0.5, 1e-12);  // 2000 px per metre
  }
  for (std::size_t k = 1; k < meshes.requested.size(); ++k) EXPECT_LE(meshes.requested[k - 1], meshes.requested[k]);
}

TEST(CompareSequence, AWrongMappingIsSeen) {
  TempDir tmp;
  const fs::path manifest = write_sequence(tmp.path(), 6, 5);
  const ObservationSequence obs = load_observations(manifest);
  ShrinkingSphere meshes;
  CompareOptions o;
  o.mapping.cycles_per_photo = 2;  // the simulation runs behind the photos
  o.registration = RegistrationMode::kNone;
  const CompareResult r = compare_sequence(obs, meshes, o);
  // Radius ratio at photo k: (1 - 0.1 k) / (1 - 0.04 k); P = 1 - ratio² for nested discs.
  for (const FrameResult& f : r.frames) {
    const double k = f.frame, ratio = (1 - 0.1 * k) / (1 - 0.04 * k);
    EXPECT_NEAR(f.pixels.P, 1 - ratio * ratio, 0.02) << f.frame;
  }
}

TEST(CompareSequence, MissingUnreadableAndBeyondFramesAreSkippedNotScored) {
  TempDir tmp;
  const fs::path manifest = write_sequence(tmp.path(), 6, 5);
  fs::remove(tmp.path() / "frames" / "f1.png");
  std::ofstream(tmp.path() / "frames" / "f2.png") << "not a png";
  const cv::Mat black = cv::Mat::zeros(180, 240, CV_8UC1);
  write_image(tmp.path() / "frames" / "f3.png", black);
  const ObservationSequence obs = load_observations(manifest);
  ShrinkingSphere meshes;
  CompareOptions o;
  o.mapping.cycles_per_photo = 5;
  o.last_cycle = 20;  // photo 5 shows cycle 25
  const CompareResult r = compare_sequence(obs, meshes, o);
  EXPECT_EQ(r.frames[1].status, "missing");
  EXPECT_EQ(r.frames[2].status, "unreadable");
  EXPECT_NE(r.frames[2].note.find("f2.png"), std::string::npos) << r.frames[2].note;
  EXPECT_EQ(r.frames[3].status, "empty_photo");
  EXPECT_EQ(r.frames[5].status, "beyond_run");
  EXPECT_EQ(r.compared, 2);
  EXPECT_EQ(r.skipped, 4);
  TempDir out;
  write_per_frame_csv(out.path() / "per_frame.csv", r.frames);
  std::ifstream in(out.path() / "per_frame.csv");
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("frame,image,status,time_s,cycle,S_A,S_B,S_I,P,P_exact,IoU", 0), 0u) << header;
  int rows = 0;
  while (std::getline(in, line)) {
    ++rows;
    if (line.find(",missing,") != std::string::npos) {
      EXPECT_NE(line.find(",,,,,"), std::string::npos) << line;
    }
  }
  EXPECT_EQ(rows, 6);
}

}  // namespace
}  // namespace meltlab::verify
