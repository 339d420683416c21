// core/image.h: the one image type's reader and writer (round trips through every format the
// project writes, the errors of broken files) and the bilinear lookup (hand-computed values).

#include <meltlab/core/error.h>
#include <meltlab/core/image.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>

#include "test_files.h"

namespace meltlab {
namespace {

namespace fs = std::filesystem;
using test::message_of;
using test::png_header;
using test::TempFolder;
using test::write_file;
using ::testing::HasSubstr;

/// A w x h image with `channels` channels whose value (x, y, c) is f(x, y, c).
template <class T, class F>
Image<T> pattern(int w, int h, int channels, F f) {
  Image<T> img(w, h, channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) img.at(x, y, c) = f(x, y, c);
  return img;
}

// ---- round trips ----

// reshape keeps an image of the asked shape as it is (storage and values) and makes any other
// shape a fresh zeroed image.
TEST(ImageShape, ReshapeKeepsTheSameShapeAndRenewsAnother) {
  ImageF im(4, 3, 2, 0.5f);
  const float* storage = im.data();
  im.reshape(4, 3, 2);
  EXPECT_EQ(im.data(), storage);
  EXPECT_EQ(im.at(3, 2, 1), 0.5f);
  im.reshape(3, 4, 2);  // the same number of values, another shape
  EXPECT_EQ(im.width(), 3);
  EXPECT_EQ(im.height(), 4);
  EXPECT_EQ(im.at(2, 3, 1), 0.0f);
  im.reshape(3, 4, 1);
  EXPECT_EQ(im.channels(), 1);
  EXPECT_EQ(im.size(), 12u);
}

TEST(ImageFiles, FloatExrRoundTripsHalfValuesExactly) {
  const TempFolder dir;
  // Multiples of 1/16 below 2048 are exact in half floats.
  const ImageF img =
      pattern<float>(7, 5, 3, [](int x, int y, int c) { return static_cast<float>(x + 7 * y + 35 * c) / 16.0f; });
  write_image(dir.path() / "a.exr", img);
  PixelFormat stored = PixelFormat::kUint8;
  const ImageF back = read_image(dir.path() / "a.exr", input_limits().image_pixels, ImageAlpha::kAsStored, &stored);
  EXPECT_EQ(stored, PixelFormat::kHalf);
  EXPECT_EQ(back, img);
}

TEST(ImageFiles, FullFloatExrKeepsEveryBit) {
  const TempFolder dir;
  const ImageF img =
      pattern<float>(6, 4, 1, [](int x, int y, int) { return 0.1f + 0.013f * static_cast<float>(x * y); });
  write_image(dir.path() / "f.exr", img, PixelFormat::kFloat);
  PixelFormat stored = PixelFormat::kUint8;
  EXPECT_EQ(read_image(dir.path() / "f.exr", input_limits().image_pixels, ImageAlpha::kAsStored, &stored), img);
  EXPECT_EQ(stored, PixelFormat::kFloat);
}

TEST(ImageFiles, EightBitPngRoundTripsAndReadsAsValueOver255) {
  const TempFolder dir;
  const Image8 img =
      pattern<std::uint8_t>(9, 4, 3, [](int x, int y, int c) { return static_cast<std::uint8_t>(x * 25 + y * 3 + c); });
  write_image(dir.path() / "a.png", img);
  PixelFormat stored = PixelFormat::kFloat;
  const ImageF back = read_image(dir.path() / "a.png", input_limits().image_pixels, ImageAlpha::kAsStored, &stored);
  EXPECT_EQ(stored, PixelFormat::kUint8);
  ASSERT_EQ(back.channels(), 3);
  ASSERT_EQ(back.width(), 9);
  for (std::size_t k = 0; k < img.size(); ++k) EXPECT_FLOAT_EQ(back.values()[k], img.values()[k] / 255.0f) << k;
}

TEST(ImageFiles, FloatToEightBitRoundsAndClamps) {
  const TempFolder dir;
  ImageF img(4, 1, 1);
  img.values() = {-1.0f, 0.5f, 0.2f, 7.0f};  // 0, round(127.5) = 128, round(51) = 51, 255
  write_image(dir.path() / "g.png", img);
  const ImageF back = read_image(dir.path() / "g.png");
  ASSERT_EQ(back.channels(), 1);
  EXPECT_FLOAT_EQ(back.values()[0] * 255.0f, 0.0f);
  EXPECT_FLOAT_EQ(back.values()[1] * 255.0f, 128.0f);
  EXPECT_FLOAT_EQ(back.values()[2] * 255.0f, 51.0f);
  EXPECT_FLOAT_EQ(back.values()[3] * 255.0f, 255.0f);
}

TEST(ImageFiles, GrayPngKeepsOneChannel) {
  const TempFolder dir;
  const Image8 img =
      pattern<std::uint8_t>(5, 3, 1, [](int x, int y, int) { return static_cast<std::uint8_t>(50 * x + y); });
  write_image(dir.path() / "gray.png", img);
  const ImageFileInfo info = read_image_info(dir.path() / "gray.png");
  EXPECT_EQ(info.width, 5);
  EXPECT_EQ(info.height, 3);
  EXPECT_EQ(info.channels, 1);
  EXPECT_EQ(info.format, PixelFormat::kUint8);
  const ImageF back = read_image(dir.path() / "gray.png");
  EXPECT_FLOAT_EQ(back.at(4, 2) * 255.0f, 202.0f);
}

TEST(ImageFiles, SixteenBitPngRoundTripsExactly) {
  const TempFolder dir;
  const ImageF img =
      pattern<float>(5, 5, 3, [](int x, int y, int c) { return static_cast<float>((x * 997 + y * 13 + c) / 65535.0); });
  write_image(dir.path() / "w.png", img, PixelFormat::kUint16);
  PixelFormat stored = PixelFormat::kUint8;
  const ImageF back = read_image(dir.path() / "w.png", input_limits().image_pixels, ImageAlpha::kAsStored, &stored);
  EXPECT_EQ(stored, PixelFormat::kUint16);
  for (std::size_t k = 0; k < img.size(); ++k)
    EXPECT_EQ(std::lround(static_cast<double>(back.values()[k]) * 65535.0),
              std::lround(static_cast<double>(img.values()[k]) * 65535.0))
        << k;
}

TEST(ImageFiles, JpegQualityIsApplied) {
  const TempFolder dir;
  const Image8 img = pattern<std::uint8_t>(64, 48, 3, [](int x, int y, int c) {
    return static_cast<std::uint8_t>(127 + 100 * std::sin(0.3 * x + 0.2 * y + c));
  });
  write_image(dir.path() / "q95.jpg", img, 95);
  write_image(dir.path() / "q20.jpg", img, 20);
  EXPECT_GT(fs::file_size(dir.path() / "q95.jpg"), fs::file_size(dir.path() / "q20.jpg"));
  // Lossy, and more so at quality 20: the mean error (chroma subsampling makes single pixels of
  // this colourful pattern far off even at 95).
  auto mean_error = [&](const char* name) {
    const ImageF back = read_image(dir.path() / name);
    EXPECT_EQ(back.width(), 64);
    double sum = 0;
    for (std::size_t k = 0; k < img.size(); ++k)
      sum += std::abs(static_cast<double>(back.values()[k]) * 255.0 - img.values()[k]);
    return sum / static_cast<double>(img.size());
  };
  const double e95 = mean_error("q95.jpg"), e20 = mean_error("q20.jpg");
  EXPECT_LT(e95, 4.0);
  EXPECT_GT(e20, e95);
  EXPECT_THAT(message_of([&] { write_image(dir.path() / "q0.jpg", img, 0); }), HasSubstr("quality"));
}

TEST(ImageFiles, AlphaAsStoredOrAssociated) {
  const TempFolder dir;
  Image8 img(2, 2, 4, 0);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) {
      img.at(x, y, 0) = 200;
      img.at(x, y, 3) = 102;  // alpha 0.4
    }
  write_image(dir.path() / "rgba.png", img);
  const ImageF stored = read_image(dir.path() / "rgba.png");
  ASSERT_EQ(stored.channels(), 4);
  EXPECT_NEAR(static_cast<double>(stored.at(1, 1, 0)) * 255.0, 200.0, 1e-3);
  const ImageF associated = read_image(dir.path() / "rgba.png", input_limits().image_pixels, ImageAlpha::kAssociated);
  EXPECT_NEAR(static_cast<double>(associated.at(1, 1, 0)) * 255.0, 200.0 * 0.4, 0.6);
}

// ---- reader errors ----

TEST(ImageFiles, ReaderErrorsAreOneLineNamingTheFile) {
  const TempFolder dir;
  const Image8 img =
      pattern<std::uint8_t>(120, 80, 3, [](int x, int y, int c) { return static_cast<std::uint8_t>(x * y + c); });
  write_image(dir.path() / "good.png", img);
  write_image(dir.path() / "good.jpg", img);
  const std::string png = test::read_file(dir.path() / "good.png");
  const std::string jpg = test::read_file(dir.path() / "good.jpg");
  write_file(dir.path() / "half.png", png.substr(0, png.size() / 2));
  write_file(dir.path() / "half.jpg", jpg.substr(0, jpg.size() / 2));
  write_file(dir.path() / "huge.png", png_header(30000, 30000));
  write_file(dir.path() / "empty.png", "");
  write_file(dir.path() / "text.exr", "not an image\n");
  fs::create_directory(dir.path() / "folder.png");
  auto error_of = [&](const std::string& name) {
    const fs::path file = dir.path() / name;
    const std::string what = message_of([&] { (void)read_image(file); });
    EXPECT_THAT(what, HasSubstr(file.string() + ": ")) << name;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    // The header-only reader sees everything but a truncated body.
    if (name.rfind("half.", 0) != 0) {
      EXPECT_EQ(message_of([&] { (void)read_image_info(file); }).rfind(file.string() + ": ", 0), 0u) << name;
    }
    return what;
  };
  EXPECT_THAT(error_of("missing.png"), HasSubstr("no such file"));
  EXPECT_THAT(error_of("empty.png"), HasSubstr("empty"));
  EXPECT_THAT(error_of("folder.png"), HasSubstr("folder"));
  EXPECT_THAT(error_of("huge.png"), HasSubstr("image_pixels"));
  EXPECT_THAT(error_of("half.png"), HasSubstr("corrupt"));
  EXPECT_THAT(error_of("half.jpg"), HasSubstr("corrupt"));
  (void)error_of("text.exr");
  // The caller's limit applies to the opened size too, and the good file still reads (no stale
  // OpenImageIO error state after all those failures).
  EXPECT_THAT(message_of([&] { (void)read_image(dir.path() / "good.png", 100 * 80); }), HasSubstr("image_pixels"));
  EXPECT_EQ(read_image(dir.path() / "good.png").width(), 120);
}

// ---- bilinear lookups ----

TEST(SampleBilinear, ExactAtPixelCentresAndLinearBetween) {
  // 3 x 2, one channel: row 0 = 0 10 20, row 1 = 100 110 120.
  const ImageF img = pattern<float>(3, 2, 1, [](int x, int y, int) { return static_cast<float>(10 * x + 100 * y); });
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 3; ++x)
      EXPECT_EQ(sample_bilinear(img, x, y, 0, ImageWrap::kClamp, ImageWrap::kClamp), 10.0 * x + 100.0 * y);
  EXPECT_DOUBLE_EQ(sample_bilinear(img, 0.5, 0.0, 0, ImageWrap::kClamp, ImageWrap::kClamp), 5.0);
  EXPECT_DOUBLE_EQ(sample_bilinear(img, 1.25, 0.5, 0, ImageWrap::kClamp, ImageWrap::kClamp), 12.5 + 50.0);
}

TEST(SampleBilinear, ClampReadsTheBorderAndRepeatTiles) {
  const ImageF img = pattern<float>(3, 2, 1, [](int x, int y, int) { return static_cast<float>(10 * x + 100 * y); });
  const auto clamp = ImageWrap::kClamp, repeat = ImageWrap::kRepeat;
  // Beyond the corners, clamped: the corner pixels.
  EXPECT_EQ(sample_bilinear(img, -3.0, -2.0, 0, clamp, clamp), 0.0);
  EXPECT_EQ(sample_bilinear(img, 9.5, 7.0, 0, clamp, clamp), 120.0);
  EXPECT_EQ(sample_bilinear(img, -0.5, 1.7, 0, clamp, clamp), 100.0);
  // Repeat in x: half-way between the last column (20) and the first (0).
  EXPECT_DOUBLE_EQ(sample_bilinear(img, 2.5, 0.0, 0, repeat, clamp), 10.0);
  EXPECT_DOUBLE_EQ(sample_bilinear(img, -0.5, 0.0, 0, repeat, clamp), 10.0);
  EXPECT_EQ(sample_bilinear(img, 3.0, 0.0, 0, repeat, clamp), 0.0);
  EXPECT_EQ(sample_bilinear(img, -4.0, 0.0, 0, repeat, clamp), 20.0);
  // Repeat in y: between row 1 and row 0 (period 2).
  EXPECT_DOUBLE_EQ(sample_bilinear(img, 1.0, 1.5, 0, clamp, repeat), 60.0);
  EXPECT_DOUBLE_EQ(sample_bilinear(img, 1.0, -0.5, 0, clamp, repeat), 60.0);
}

TEST(SampleBilinear, InsideIsBitwiseTheClampedLookupForPointsInside) {
  // Every point of a grid over [0, w-1] x [0, h-1] with the edges themselves, a one-row and a
  // one-column image (the degenerate axes), and values of mixed sign and scale.
  for (const auto& [w, h] : {std::pair{7, 5}, std::pair{1, 4}, std::pair{6, 1}, std::pair{2, 2}}) {
    const ImageF img =
        pattern<float>(w, h, 1, [](int x, int y, int) { return std::sin(1.3f * x + 0.7f * y) * (1 + 1000.0f * y); });
    for (int i = 0; i <= 40; ++i)
      for (int j = 0; j <= 40; ++j) {
        const double x = (w - 1) * i / 40.0, y = (h - 1) * j / 40.0;
        ASSERT_EQ(sample_bilinear_inside(img, x, y),
                  sample_bilinear(img, x, y, 0, ImageWrap::kClamp, ImageWrap::kClamp))
            << w << "x" << h << " at " << x << ", " << y;
      }
  }
}

TEST(SampleBilinear, RgbIsBitwiseThePerChannelLookup) {
  const ImageF img = pattern<float>(5, 4, 3, [](int x, int y, int c) { return std::sin(1.3f * x + 0.7f * y + c); });
  for (double x : {-1.3, 0.0, 0.37, 2.5, 4.9, 7.1})
    for (double y : {-0.2, 0.5, 1.0, 3.7, 5.2})
      for (ImageWrap wy : {ImageWrap::kClamp, ImageWrap::kRepeat}) {
        const Eigen::Vector3d rgb = sample_bilinear_rgb(img, x, y, ImageWrap::kRepeat, wy);
        for (int c = 0; c < 3; ++c)
          EXPECT_EQ(rgb[c], sample_bilinear(img, x, y, c, ImageWrap::kRepeat, wy)) << x << " " << y;
      }
}

}  // namespace
}  // namespace meltlab
