// segment_image on synthetic photos whose true shape is known exactly.
//
// The realistic scene: bright ice (a disc with an off-centre hole) on a dark, slightly
// textured ground, lit unevenly (30 % brighter on one side), seen through a slightly soft
// lens, with sensor noise, then JPEG-compressed. Why P <= 0.02 is the right bound: a
// correct segmentation differs from the true shape only along the boundary, by the
// pixelisation of the true shape (A samples pixel centres) plus the edge displacement
// that comes from thresholding a blurred edge away from its half-way level (Otsu's
// threshold is one number for the whole image while the local half-way level follows
// the lighting: here up to ~0.4 px). With perimeter L and area S the expected P is about
// L * (0.3..0.5 px) / S: for this scene (L ~ 1000 px, S ~ 41000 px^2) 0.007..0.012; 0.02
// leaves margin for noise but is far below what a wrong threshold (a whole pixel ring,
// ~0.025) or a lost hole (0.09) would give.

#include <meltlab/core/error.h>
#include <meltlab/verify/observations.h>
#include <meltlab/verify/region.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

#include "test_util.h"

namespace meltlab::verify {
namespace {

using Inside = std::function<bool(double, double)>;

/// Coverage (0..1) of each pixel by the shape: 8x8 supersampling.
cv::Mat coverage(const Inside& inside, int w, int h) {
  cv::Mat cov(h, w, CV_32FC1);
  constexpr int n = 8;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int count = 0;
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) count += inside(x - 0.5 + (i + 0.5) / n, y - 0.5 + (j + 0.5) / n);
      cov.at<float>(y, x) = static_cast<float>(count) / (n * n);
    }
  }
  return cov;
}

/// Pixel-centre rasterisation of the shape (the "true" mask A).
cv::Mat truth_mask(const Inside& inside, int w, int h) {
  cv::Mat m(h, w, CV_8UC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) m.at<unsigned char>(y, x) = inside(x, y) ? 255 : 0;
  return m;
}

/// |A xor B| / |A or B|.
double p_measure(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat x, o;
  cv::bitwise_xor(a, b, x);
  cv::bitwise_or(a, b, o);
  const int n = cv::countNonZero(o);
  return n == 0 ? 0.0 : static_cast<double>(cv::countNonZero(x)) / n;
}

/// A smooth random texture with zero mean and unit standard deviation.
cv::Mat texture(int w, int h, double sigma_px, unsigned seed) {
  cv::Mat t(h, w, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(t, cv::RNG::NORMAL, 0, 1);
  if (sigma_px > 0) cv::GaussianBlur(t, t, cv::Size(0, 0), sigma_px);
  cv::Scalar mean, stddev;
  cv::meanStdDev(t, mean, stddev);
  t = (t - mean[0]) / stddev[0];
  return t;
}

struct SceneOptions {
  cv::Scalar ice{225, 215, 205};  // BGR, 8-bit scale
  cv::Scalar ground{38, 42, 50};
  double ground_texture = 6;  // amplitude of the ground's texture
  double light_min = 0.75;    // lighting: light_min at x = 0 ... 1 at x = w
  double lens_sigma = 0.8;
  double noise = 4;
  unsigned seed = 1;
};

/// The photo (CV_32FC3, 8-bit scale, unclamped) of a shape.
cv::Mat photo(const Inside& inside, int w, int h, const SceneOptions& o) {
  const cv::Mat cov = coverage(inside, w, h);
  const cv::Mat coarse = texture(w, h, 3.0, o.seed);
  const cv::Mat fine = texture(w, h, 0.0, o.seed + 1);
  cv::Mat img(h, w, CV_32FC3);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double light = o.light_min + (1.0 - o.light_min) * x / w;
      const double c = cov.at<float>(y, x);
      const double tex = o.ground_texture * (0.8 * static_cast<double>(coarse.at<float>(y, x)) +
                                             0.4 * static_cast<double>(fine.at<float>(y, x)));
      cv::Vec3f& px = img.at<cv::Vec3f>(y, x);
      for (int k = 0; k < 3; ++k) {
        const double v = c * o.ice[k] + (1 - c) * (o.ground[k] + tex);
        px[k] = static_cast<float>(light * v);
      }
    }
  }
  if (o.lens_sigma > 0) cv::GaussianBlur(img, img, cv::Size(0, 0), o.lens_sigma);
  if (o.noise > 0) {
    cv::Mat n(h, w, CV_32FC3);
    cv::RNG rng(o.seed + 2);
    rng.fill(n, cv::RNG::NORMAL, 0, o.noise);
    img += n;
  }
  return img;
}

cv::Mat to8(const cv::Mat& f) {
  cv::Mat out;
  f.convertTo(out, CV_8U);
  return out;
}

/// JPEG round trip through meltlab's writer and reader at the given quality.
cv::Mat jpeg(const cv::Mat& bgr8, int quality) {
  test::TempDir dir;
  const auto file = dir / "photo.jpg";
  meltlab::write_image(file, image_from_mat(bgr8), PixelFormat::kUint8, quality);
  return read_image(file);
}

// The ice: a disc with an off-centre round hole.
constexpr int kW = 640, kH = 480;
constexpr double kCx = 330.3, kCy = 236.6, kR = 150.0;
constexpr double kHx = kCx + 30.2, kHy = kCy - 20.7, kHr = 40.0;
bool ice_with_hole(double x, double y) {
  return std::hypot(x - kCx, y - kCy) < kR && std::hypot(x - kHx, y - kHy) >= kHr;
}
const double kTrueArea = std::numbers::pi * (kR * kR - kHr * kHr);

TEST(Segmentation, DefaultsOnARealisticPhoto) {
  const cv::Mat img = jpeg(to8(photo(ice_with_hole, kW, kH, {})), 85);
  const Segmentation seg = segment_image(img, SegmentationSettings{});
  const cv::Mat truth = truth_mask(ice_with_hole, kW, kH);

  ASSERT_EQ(seg.mask.type(), CV_8UC1);
  ASSERT_EQ(seg.mask.size(), img.size());
  ASSERT_EQ(seg.probability.type(), CV_32FC1);
  const double p = p_measure(truth, seg.mask);
  EXPECT_LE(p, 0.02);
  EXPECT_EQ(seg.area_px, cv::countNonZero(seg.mask));
  EXPECT_GT(seg.threshold_used, 60);
  EXPECT_LT(seg.threshold_used, 170);
  // The hole is kept: one polygon with one hole.
  EXPECT_EQ(seg.mask.at<unsigned char>(static_cast<int>(kHy), static_cast<int>(kHx)), 0);
  ASSERT_EQ(seg.region.size(), 1U);
  EXPECT_EQ(seg.region[0].holes.size(), 1U);
  // Sub-pixel area within 1 %; the pixel count is a coarser estimate.
  const double area = region_area(seg.region);
  EXPECT_NEAR(area / kTrueArea, 1.0, 0.01) << "pixel count " << seg.area_px << " true " << kTrueArea;
  // Probability in [0, 1] and on the mask's side of 0.5 at every pixel.
  double lo = 0, hi = 0;
  cv::minMaxLoc(seg.probability, &lo, &hi);
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.0);
  EXPECT_EQ(cv::countNonZero((seg.probability > 0.5) != (seg.mask > 0)), 0);
  RecordProperty("P", std::to_string(p));
  RecordProperty("area_ratio", std::to_string(area / kTrueArea));
}

TEST(Segmentation, SubPixelAreaIsMoreAccurateThanPixelCountOnACleanEdge) {
  // A clean anti-aliased small disc: the sub-pixel contour follows the edge.
  const auto disc = [](double x, double y) { return std::hypot(x - 50.37, y - 41.81) < 17.3; };
  SceneOptions o;
  o.ground_texture = 0;
  o.light_min = 1;
  o.noise = 0;
  o.lens_sigma = 0;
  SegmentationSettings s;
  s.method = SegmentationSettings::Method::kGlobal;
  s.threshold = (o.ice[0] + o.ground[0]) / 2;  // the half-way level: the true edge
  s.blur_sigma_px = 0;
  s.channel = "blue";
  const cv::Mat img = photo(disc, 100, 90, o);
  const Segmentation seg = segment_image(img / 255.0, s);  // float input, [0, 1]
  const double truth = std::numbers::pi * 17.3 * 17.3;
  EXPECT_NEAR(region_area(seg.region) / truth, 1.0, 0.003);
}

TEST(Segmentation, SixteenBitAndFloatInputsAgreeWithEightBit) {
  const cv::Mat f = photo(ice_with_hole, kW, kH, {});
  cv::Mat f16, f01;
  f.convertTo(f16, CV_16U, 257.0);
  f01 = f / 255.0;
  const Segmentation a = segment_image(to8(f), {});
  const Segmentation b = segment_image(f16, {});
  const Segmentation c = segment_image(f01, {});
  EXPECT_LE(p_measure(a.mask, b.mask), 0.002);
  EXPECT_LE(p_measure(a.mask, c.mask), 0.002);
}

TEST(Segmentation, GreyInputAndEveryChannel) {
  const cv::Mat img = to8(photo(ice_with_hole, kW, kH, {}));
  const cv::Mat truth = truth_mask(ice_with_hole, kW, kH);
  for (const char* ch : {"gray", "value", "lightness", "max", "red", "green", "blue"}) {
    SegmentationSettings s;
    s.channel = ch;
    EXPECT_LE(p_measure(truth, segment_image(img, s).mask), 0.02) << ch;
  }
  cv::Mat grey;
  cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
  EXPECT_LE(p_measure(truth, segment_image(grey, {}).mask), 0.02);
}

TEST(Segmentation, ChannelSelectsColour) {
  // A red object on a green ground of the same brightness: only the red channel sees it.
  const auto disc = [](double x, double y) { return std::hypot(x - 60, y - 50) < 25; };
  SceneOptions o;
  o.ice = cv::Scalar(20, 20, 200);
  o.ground = cv::Scalar(20, 200, 20);
  o.ground_texture = 0;
  const cv::Mat img = to8(photo(disc, 120, 100, o));
  SegmentationSettings s;
  s.channel = "red";
  EXPECT_LE(p_measure(truth_mask(disc, 120, 100), segment_image(img, s).mask), 0.03);
  s.channel = "green";
  s.object_darker = true;
  EXPECT_LE(p_measure(truth_mask(disc, 120, 100), segment_image(img, s).mask), 0.03);
}

TEST(Segmentation, GlobalThreshold) {
  SceneOptions o;
  o.light_min = 1;
  const cv::Mat img = to8(photo(ice_with_hole, kW, kH, o));
  SegmentationSettings s;
  s.method = SegmentationSettings::Method::kGlobal;
  s.threshold = 130;
  const Segmentation seg = segment_image(img, s);
  EXPECT_EQ(seg.threshold_used, 130);
  EXPECT_LE(p_measure(truth_mask(ice_with_hole, kW, kH), seg.mask), 0.02);
  // A threshold above the ice finds nothing, without error.
  s.threshold = 250;
  EXPECT_EQ(segment_image(img, s).area_px, 0);
}

// Small bright pieces under lighting so uneven that the ground on the bright side is
// brighter than the ice on the dark side: no single threshold works, adaptive does.
bool pieces(double x, double y) {
  for (int i = 0; i < 6; ++i) {
    const double cx = 60 + 100 * i + 0.3, cy = 80 + 60 * (i % 2) + 0.6;
    if (std::hypot(x - cx, y - cy) < 14) return true;
  }
  return false;
}

TEST(Segmentation, AdaptiveHandlesStrongUnevenLighting) {
  SceneOptions o;
  o.ice = cv::Scalar(200, 200, 200);
  o.ground = cv::Scalar(110, 110, 110);
  o.light_min = 0.35;
  o.ground_texture = 4;
  const int w = 640, h = 220;
  const cv::Mat img = to8(photo(pieces, w, h, o));
  const cv::Mat truth = truth_mask(pieces, w, h);
  SegmentationSettings s;
  s.largest_component = false;
  s.method = SegmentationSettings::Method::kAdaptive;
  s.adaptive_offset = -15;
  const Segmentation seg = segment_image(img, s);
  EXPECT_LE(p_measure(truth, seg.mask), 0.12);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(seg.mask.at<unsigned char>(80 + 60 * (i % 2), 60 + 100 * i), 255) << "piece " << i;
  }
  EXPECT_EQ(seg.region.size(), 6U);
  // Otsu cannot: one threshold for the whole image.
  s.method = SegmentationSettings::Method::kOtsu;
  EXPECT_GT(p_measure(truth, segment_image(img, s).mask), 0.3);
}

TEST(Segmentation, BackgroundSubtraction) {
  // A strongly striped ground with an object of similar brightness to the bright stripes:
  // thresholds fail, the difference to the empty scene does not.
  const int w = 200, h = 160;
  const auto disc = [](double x, double y) { return std::hypot(x - 100.4, y - 80.2) < 40; };
  cv::Mat ground(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      ground.at<cv::Vec3b>(y, x) = ((x / 10) % 2) ? cv::Vec3b(200, 200, 200) : cv::Vec3b(30, 30, 30);
  cv::Mat scene = ground.clone();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (disc(x, y)) scene.at<cv::Vec3b>(y, x) = cv::Vec3b(120, 120, 120);
  cv::Mat noise(h, w, CV_8UC3);
  cv::RNG(3).fill(noise, cv::RNG::NORMAL, 0, 3);
  cv::Mat noisy_scene;
  cv::add(scene, noise, noisy_scene);
  test::TempDir dir;
  write_image(dir / "empty.png", ground);
  SegmentationSettings s;
  s.method = SegmentationSettings::Method::kBackground;
  s.background = dir / "empty.png";
  s.blur_sigma_px = 0.7;
  s.fill_holes = false;
  const Segmentation seg = segment_image(noisy_scene, s);
  EXPECT_EQ(seg.threshold_used, s.background_difference);
  EXPECT_LE(p_measure(truth_mask(disc, w, h), seg.mask), 0.03);
  // A background of another size is an error naming it.
  write_image(dir / "small.png", cv::Mat(10, 10, CV_8UC3, cv::Scalar(0)));
  s.background = dir / "small.png";
  try {
    segment_image(noisy_scene, s);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("small.png"));
  }
  s.background = dir / "missing.png";
  EXPECT_THROW(segment_image(noisy_scene, s), InputError);
}

TEST(Segmentation, ObjectDarker) {
  SceneOptions o;
  o.ice = cv::Scalar(30, 30, 35);
  o.ground = cv::Scalar(190, 195, 200);
  const cv::Mat img = to8(photo(ice_with_hole, kW, kH, o));
  SegmentationSettings s;
  s.object_darker = true;
  const Segmentation seg = segment_image(img, s);
  EXPECT_LE(p_measure(truth_mask(ice_with_hole, kW, kH), seg.mask), 0.02);
  EXPECT_GT(seg.threshold_used, 60);  // in the channel's own scale, between the two levels
  EXPECT_LT(seg.threshold_used, 180);
  // Without the flag the ground (largest bright part) is taken instead.
  EXPECT_GT(p_measure(truth_mask(ice_with_hole, kW, kH), segment_image(img, {}).mask), 0.5);
}

// Three pieces of different size plus specks.
bool three_pieces(double x, double y) {
  return std::hypot(x - 60, y - 60) < 35 || std::hypot(x - 160, y - 60) < 20 || std::hypot(x - 240, y - 60) < 10 ||
         std::hypot(x - 160, y - 130) < 2.5 || std::hypot(x - 40, y - 140) < 3;
}

TEST(Segmentation, LargestComponentVersusAll) {
  const int w = 300, h = 170;
  const cv::Mat img = to8(photo(three_pieces, w, h, {}));
  SegmentationSettings s;
  Segmentation seg = segment_image(img, s);
  EXPECT_EQ(seg.region.size(), 1U);
  EXPECT_EQ(seg.mask.at<unsigned char>(60, 60), 255);
  EXPECT_EQ(seg.mask.at<unsigned char>(60, 160), 0);
  EXPECT_NEAR(seg.area_px, std::numbers::pi * 35 * 35, 40);

  s.largest_component = false;
  s.open_radius_px = 0;  // keep the specks for the size filter to remove
  seg = segment_image(img, s);
  EXPECT_EQ(seg.region.size(), 3U);
  EXPECT_EQ(seg.mask.at<unsigned char>(60, 240), 255);
  EXPECT_EQ(seg.mask.at<unsigned char>(130, 160), 0);
  EXPECT_EQ(seg.mask.at<unsigned char>(140, 40), 0);

  s.min_component_px = 0;
  seg = segment_image(img, s);
  EXPECT_EQ(seg.mask.at<unsigned char>(140, 40), 255);
}

TEST(Segmentation, RoiRestrictsTheMask) {
  const int w = 300, h = 170;
  const cv::Mat img = to8(photo(three_pieces, w, h, {}));
  const cv::Rect roi(120, 20, 80, 80);  // around the middle piece only
  const Segmentation seg = segment_image(img, {}, roi);
  EXPECT_EQ(seg.mask.size(), img.size());
  EXPECT_EQ(seg.mask.at<unsigned char>(60, 60), 0);
  EXPECT_EQ(seg.mask.at<unsigned char>(60, 160), 255);
  cv::Mat outside = seg.mask.clone();
  outside(roi).setTo(0);
  EXPECT_EQ(cv::countNonZero(outside), 0);
  EXPECT_NEAR(seg.area_px, std::numbers::pi * 20 * 20, 30);
  EXPECT_THROW(segment_image(img, {}, cv::Rect(250, 20, 80, 80)), InputError);
  EXPECT_THROW(segment_image(img, {}, cv::Rect(10, 10, 0, 5)), InputError);
}

TEST(Segmentation, FillHoles) {
  const cv::Mat img = to8(photo(ice_with_hole, kW, kH, {}));
  SegmentationSettings s;
  s.fill_holes = true;
  const Segmentation seg = segment_image(img, s);
  EXPECT_EQ(seg.mask.at<unsigned char>(static_cast<int>(kHy), static_cast<int>(kHx)), 255);
  ASSERT_EQ(seg.region.size(), 1U);
  EXPECT_TRUE(seg.region[0].holes.empty());
  EXPECT_NEAR(region_area(seg.region) / (std::numbers::pi * kR * kR), 1.0, 0.01);
}

TEST(Segmentation, EmptyResultsAreNotErrors) {
  for (const int type : {CV_8UC1, CV_8UC3, CV_16UC3, CV_32FC1}) {
    const cv::Mat black(50, 60, type, cv::Scalar::all(0));
    Segmentation seg;
    ASSERT_NO_THROW(seg = segment_image(black, {})) << type;
    EXPECT_EQ(seg.area_px, 0);
    EXPECT_EQ(cv::countNonZero(seg.mask), 0);
    EXPECT_TRUE(seg.region.empty());
    EXPECT_EQ(seg.mask.size(), black.size());
  }
  const cv::Mat white(50, 60, CV_8UC3, cv::Scalar::all(255));
  EXPECT_NO_THROW(segment_image(white, {}));
}

// The photo after the ice has gone: only the textured, unevenly lit ground. Otsu always
// splits an image in two; the contrast check must recognise that no object is there.
TEST(Segmentation, BareGroundIsEmptyNotAnObject) {
  const Inside nothing = [](double, double) { return false; };
  const cv::Mat bare = jpeg(to8(photo(nothing, 320, 240, SceneOptions{})), 85);
  const Segmentation seg = segment_image(bare, {});
  EXPECT_EQ(seg.area_px, 0) << "contrast " << seg.contrast;
  EXPECT_TRUE(seg.region.empty());
  SegmentationSettings off;
  off.min_contrast = 0;
  const Segmentation split = segment_image(bare, off);
  EXPECT_GT(split.area_px, 0) << "without the check Otsu segments ground texture (the case the check exists for)";
  EXPECT_LT(split.contrast, SegmentationSettings{}.min_contrast);
  // With the ice present the contrast is far above the default limit.
  const cv::Mat with_ice = jpeg(to8(photo(ice_with_hole, 320, 240, SceneOptions{})), 85);
  const Segmentation ice = segment_image(with_ice, {});
  EXPECT_GT(ice.area_px, 0);
  EXPECT_GT(ice.contrast, 2 * SegmentationSettings{}.min_contrast);
}

TEST(Segmentation, BadInputsAreErrors) {
  EXPECT_THROW(segment_image(cv::Mat(), {}), InputError);
  const cv::Mat img(20, 20, CV_8UC1, cv::Scalar(0));
  SegmentationSettings s;
  s.method = SegmentationSettings::Method::kAdaptive;
  s.adaptive_block_px = 50;
  EXPECT_THROW(segment_image(img, s), InputError);
  s = {};
  s.channel = "hue";
  EXPECT_THROW(segment_image(img, s), InputError);
  s = {};
  s.method = SegmentationSettings::Method::kBackground;  // without a background image
  EXPECT_THROW(segment_image(img, s), InputError);
}

}  // namespace
}  // namespace meltlab::verify
