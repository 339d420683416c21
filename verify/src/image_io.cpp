// The edge between meltlab's image type and OpenCV: verify calls OpenCV on cv::Mat (BGR), the
// files are read and written by core's one reader and writer (meltlab/core/image.h).

#include "obs_detail.h"

#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/verify/observations.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace meltlab::verify {

namespace fs = std::filesystem;

namespace {

// OpenCV's channel order: BGR for colour, the channel itself for grey.
int rgb_channel_of_bgr(int bgr_channel, int channels) {
  return channels >= 3 && bgr_channel < 3 ? 2 - bgr_channel : bgr_channel;
}

template <class T>
void fill_from_image(const ImageF& image, cv::Mat& mat, double scale) {
  const int channels = mat.channels();
  for (int y = 0; y < mat.rows; ++y) {
    T* out = mat.ptr<T>(y);
    for (int x = 0; x < mat.cols; ++x)
      for (int c = 0; c < channels; ++c) {
        const double v = image.at(x, y, rgb_channel_of_bgr(c, channels));
        if constexpr (std::is_same_v<T, float>) {
          out[x * channels + c] = static_cast<float>(v);
        } else {
          // The stored integers exactly: OpenImageIO read them as integer / max.
          out[x * channels + c] = static_cast<T>(std::lround(std::clamp(v, 0.0, 1.0) * scale));
        }
      }
  }
}

template <class T>
void fill_from_mat(const cv::Mat& mat, ImageF& image, double scale) {
  const int channels = mat.channels();
  for (int y = 0; y < mat.rows; ++y) {
    const T* in = mat.ptr<T>(y);
    for (int x = 0; x < mat.cols; ++x)
      for (int c = 0; c < channels; ++c)
        image.at(x, y, rgb_channel_of_bgr(c, channels)) =
            std::is_same_v<T, float> ? static_cast<float>(in[x * channels + c])
                                     : static_cast<float>(static_cast<double>(in[x * channels + c]) / scale);
  }
}

}  // namespace

cv::Mat mat_from_image(const ImageF& image, PixelFormat format) {
  // 1 or 2 channels (grey, grey + alpha) -> grey; 3 or more (RGB, RGBA, ...) -> the first three as BGR.
  const int channels = image.channels() >= 3 ? 3 : 1;
  switch (format) {
    case PixelFormat::kUint8: {
      cv::Mat mat(image.height(), image.width(), CV_MAKETYPE(CV_8U, channels));
      fill_from_image<std::uint8_t>(image, mat, 255.0);
      return mat;
    }
    case PixelFormat::kUint16: {
      cv::Mat mat(image.height(), image.width(), CV_MAKETYPE(CV_16U, channels));
      fill_from_image<std::uint16_t>(image, mat, 65535.0);
      return mat;
    }
    case PixelFormat::kHalf:
    case PixelFormat::kFloat:
      break;
  }
  cv::Mat mat(image.height(), image.width(), CV_MAKETYPE(CV_32F, channels));
  fill_from_image<float>(image, mat, 1.0);
  return mat;
}

ImageF image_from_mat(const cv::Mat& mat, PixelFormat* format) {
  if (mat.empty()) throw InputError("cannot convert an empty cv::Mat to an image");
  ImageF image(mat.cols, mat.rows, mat.channels());
  switch (mat.depth()) {
    case CV_8U:
      fill_from_mat<std::uint8_t>(mat, image, 255.0);
      if (format) *format = PixelFormat::kUint8;
      break;
    case CV_16U:
      fill_from_mat<std::uint16_t>(mat, image, 65535.0);
      if (format) *format = PixelFormat::kUint16;
      break;
    case CV_32F:
      fill_from_mat<float>(mat, image, 1.0);
      if (format) *format = PixelFormat::kFloat;
      break;
    default:
      throw InputError(fmt::format("cannot convert pixels of OpenCV depth {} (8U, 16U or 32F only)", mat.depth()));
  }
  return image;
}

namespace detail {

cv::Size read_image_size(const fs::path& file) {
  const ImageFileInfo info = read_image_info(file);
  return {info.width, info.height};
}

}  // namespace detail

cv::Mat read_image(const fs::path& file) {
  PixelFormat stored = PixelFormat::kUint8;
  const ImageF image = meltlab::read_image(file, input_limits().image_pixels, ImageAlpha::kAsStored, &stored);
  return mat_from_image(image, stored);
}

void write_image(const fs::path& file, const cv::Mat& image) {
  if (image.empty()) throw InputError(fmt::format("{}: cannot write an empty image", file.string()));
  if (image.depth() != CV_8U && image.depth() != CV_16U && image.depth() != CV_32F)
    throw InputError(
        fmt::format("{}: cannot write pixels of OpenCV depth {} (8U, 16U or 32F only)", file.string(), image.depth()));
  PixelFormat stored = PixelFormat::kUint8;
  const ImageF pixels = image_from_mat(image, &stored);
  meltlab::write_image(file, pixels, stored);
}

}  // namespace meltlab::verify
