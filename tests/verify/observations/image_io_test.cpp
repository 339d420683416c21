// read_image / write_image: round trips through every format we meet, and broken files.

#include "../../../verify/src/obs_detail.h"

#include <meltlab/core/error.h>
#include <meltlab/verify/observations.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include <cmath>
#include <random>

#include "test_util.h"

namespace meltlab::verify {
namespace {

using ::testing::HasSubstr;

/// A smooth colourful test pattern of the given type.
cv::Mat pattern(int type, int width = 97, int height = 61) {
  cv::Mat img(height, width, type);
  const int ch = img.channels();
  const double full = img.depth() == CV_8U ? 255.0 : (img.depth() == CV_16U ? 65535.0 : 1.0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      for (int c = 0; c < ch; ++c) {
        const double v = 0.5 + 0.45 * std::sin(0.07 * x * (c + 1) + 0.11 * y - c);
        const double value = v * full;
        switch (img.depth()) {
          case CV_8U:
            img.ptr<unsigned char>(y)[x * ch + c] = cv::saturate_cast<unsigned char>(value);
            break;
          case CV_16U:
            img.ptr<unsigned short>(y)[x * ch + c] = cv::saturate_cast<unsigned short>(value);
            break;
          default:
            img.ptr<float>(y)[x * ch + c] = static_cast<float>(value);
            break;
        }
      }
    }
  }
  return img;
}

double max_abs_diff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat da, db;
  a.convertTo(da, CV_64F);
  b.convertTo(db, CV_64F);
  return cv::norm(da, db, cv::NORM_INF);
}

std::string error_of(const std::filesystem::path& file) {
  try {
    read_image(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

struct RoundTrip {
  const char* file;
  int type;
  double tolerance;  // in the type's units
};

TEST(ImageIo, RoundTrips) {
  const RoundTrip cases[] = {
      {"grey8.png", CV_8UC1, 0},  {"rgb8.png", CV_8UC3, 0},     {"grey16.png", CV_16UC1, 0}, {"rgb16.png", CV_16UC3, 0},
      {"rgb8.tif", CV_8UC3, 0},   {"grey16.tiff", CV_16UC1, 0}, {"float.tif", CV_32FC1, 0},  {"rgbf.exr", CV_32FC3, 0},
      {"greyf.exr", CV_32FC1, 0}, {"rgb8.jpg", CV_8UC3, 40},    {"grey8.jpeg", CV_8UC1, 40},
  };
  test::TempDir dir;
  for (const RoundTrip& c : cases) {
    const cv::Mat img = pattern(c.type);
    const auto file = dir / c.file;
    ASSERT_NO_THROW(write_image(file, img)) << c.file;
    const cv::Mat back = read_image(file);
    EXPECT_EQ(back.type(), c.type) << c.file;
    ASSERT_EQ(back.size(), img.size()) << c.file;
    EXPECT_LE(max_abs_diff(back, img), c.tolerance) << c.file;
    EXPECT_EQ(detail::read_image_size(file), img.size()) << c.file;
  }
}

TEST(ImageIo, ColourOrderIsBgr) {
  test::TempDir dir;
  cv::Mat img(8, 8, CV_8UC3, cv::Scalar(10, 20, 250));  // B, G, R: red
  write_image(dir / "red.png", img);
  // The file (and meltlab's image type) holds RGB: the first channel must be red.
  const ImageF rgb = meltlab::read_image(dir / "red.png");
  EXPECT_EQ(std::lround(static_cast<double>(rgb.at(0, 0, 0)) * 255.0), 250);
  EXPECT_EQ(std::lround(static_cast<double>(rgb.at(0, 0, 2)) * 255.0), 10);
  const cv::Mat back = read_image(dir / "red.png");
  EXPECT_EQ(back.at<cv::Vec3b>(3, 3), cv::Vec3b(10, 20, 250));
}

TEST(ImageIo, AlphaIsDropped) {
  test::TempDir dir;
  cv::Mat img(5, 7, CV_8UC4, cv::Scalar(1, 2, 3, 128));
  write_image(dir / "rgba.png", img);
  const cv::Mat back = read_image(dir / "rgba.png");
  EXPECT_EQ(back.type(), CV_8UC3);
  EXPECT_EQ(back.at<cv::Vec3b>(2, 2), cv::Vec3b(1, 2, 3));
}

TEST(ImageIo, BrokenFilesAreInputErrorsNamingTheFile) {
  test::TempDir dir;
  write_image(dir / "good.png", pattern(CV_8UC3, 300, 200));
  write_image(dir / "good.jpg", pattern(CV_8UC3, 300, 200));
  const std::string png = test::read_file(dir / "good.png");
  const std::string jpg = test::read_file(dir / "good.jpg");
  test::write_file(dir / "half.png", png.substr(0, png.size() / 2));
  test::write_file(dir / "half.jpg", jpg.substr(0, jpg.size() / 2));
  test::write_file(dir / "tiny.png", png.substr(0, 20));
  test::write_file(dir / "zero.png", "");
  std::mt19937 rng(7);
  std::string noise(5000, '\0');
  for (char& ch : noise) ch = static_cast<char>(rng() & 0xFF);
  test::write_file(dir / "noise.png", noise);
  test::write_file(dir / "noise.jpg", noise);
  test::write_file(dir / "noise.exr", noise);
  test::write_file(dir / "text.tif", "this is not a TIFF file\n");
  std::filesystem::create_directory(dir / "folder.png");

  for (const char* name : {"half.png", "half.jpg", "tiny.png", "zero.png", "noise.png", "noise.jpg", "noise.exr",
                           "text.tif", "folder.png", "missing.png"}) {
    const std::string msg = error_of(dir / name);
    EXPECT_THAT(msg, HasSubstr((dir / name).string() + ": ")) << name;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
  EXPECT_THAT(error_of(dir / "zero.png"), HasSubstr("empty"));
  EXPECT_THAT(error_of(dir / "folder.png"), HasSubstr("folder"));
  EXPECT_THAT(error_of(dir / "missing.png"), HasSubstr("no such file"));
  EXPECT_THROW(detail::read_image_size(dir / "zero.png"), InputError);
  EXPECT_THROW(detail::read_image_size(dir / "noise.png"), InputError);
  // The good ones still read after all those failures (no stale OIIO error state).
  EXPECT_EQ(read_image(dir / "good.png").size(), cv::Size(300, 200));
}

TEST(ImageIo, MatConversionsAreExactInverses) {
  for (int type : {CV_8UC1, CV_8UC3, CV_16UC1, CV_16UC3, CV_32FC1, CV_32FC3}) {
    const cv::Mat img = pattern(type);
    PixelFormat format = PixelFormat::kHalf;
    const ImageF image = image_from_mat(img, &format);
    EXPECT_EQ(image.channels(), img.channels());
    const cv::Mat back = mat_from_image(image, format);
    EXPECT_EQ(back.type(), type);
    EXPECT_EQ(max_abs_diff(back, img), 0.0) << type;
  }
  // BGR in OpenCV is RGB in the image type.
  const cv::Mat bgr(1, 1, CV_8UC3, cv::Scalar(0, 0, 255));
  EXPECT_EQ(image_from_mat(bgr).at(0, 0, 0), 1.0f);
  EXPECT_THROW(image_from_mat(cv::Mat(2, 2, CV_64FC1)), InputError);
}

TEST(ImageIo, WriteRefusesWhatItCannotWrite) {
  test::TempDir dir;
  EXPECT_THROW(write_image(dir / "e.png", cv::Mat()), InputError);
  EXPECT_THROW(write_image(dir / "d.png", cv::Mat(4, 4, CV_64FC1, cv::Scalar(0))), InputError);
  EXPECT_THROW(write_image(dir / "x.unknown-format", pattern(CV_8UC1)), InputError);
  EXPECT_THROW(write_image(dir / "no-such-folder" / "a.png", pattern(CV_8UC1)), std::exception);
}

}  // namespace
}  // namespace meltlab::verify
