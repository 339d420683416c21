#pragma once
// The one image type of meltlab: a width x height grid of pixels with `channels` values each,
// interleaved, row-major, row 0 at the top. Pixel convention as in render/camera.h: x grows to
// the right, y downwards, integer coordinates are pixel CENTRES.
//
// Colour images are RGB (OpenImageIO's order) unless a function says otherwise; OpenCV's BGR
// cv::Mat stays inside verify/ and the photo renderer, converted at that edge.
// Values: float images are linear radiance or any scalar field; 8-bit images are encoded
// display values 0..255.

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace meltlab {

template <class T>
class Image {
 public:
  using value_type = T;

  Image() = default;
  Image(int width, int height, int channels, T fill = T{})
      : width_(width), height_(height), channels_(channels),
        data_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * static_cast<std::size_t>(channels),
              fill) {}

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  bool empty() const { return data_.empty(); }
  /// Number of values (width * height * channels).
  std::size_t size() const { return data_.size(); }

  std::size_t index(int x, int y, int c = 0) const {
    return (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)) *
               static_cast<std::size_t>(channels_) +
           static_cast<std::size_t>(c);
  }
  T& at(int x, int y, int c = 0) { return data_[index(x, y, c)]; }
  const T& at(int x, int y, int c = 0) const { return data_[index(x, y, c)]; }
  /// The values of row y (width * channels of them).
  T* row(int y) { return data_.data() + index(0, y); }
  const T* row(int y) const { return data_.data() + index(0, y); }
  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  std::vector<T>& values() { return data_; }
  const std::vector<T>& values() const { return data_; }

  bool operator==(const Image& o) const = default;

 private:
  int width_ = 0, height_ = 0, channels_ = 0;
  std::vector<T> data_;
};

using ImageF = Image<float>;
using Image8 = Image<std::uint8_t>;

/// What a lookup outside [0, width-1] x [0, height-1] (pixel centres) reads.
enum class ImageWrap {
  kClamp,   ///< the nearest border pixel
  kRepeat,  ///< the image tiles the plane
};

/// Bilinear lookup of channel c at continuous pixel coordinates (x, y), pixel centres at
/// integers, with the given addressing per axis.
double sample_bilinear(const ImageF& image, double x, double y, int c, ImageWrap wrap_x, ImageWrap wrap_y);

/// The largest image a reader accepts unless told otherwise, in pixels (width * height):
/// 2^28 = 268 M pixels (16384 x 16384); a corrupt or hostile header must not make a reader
/// allocate gigabytes. Readers take the limit as an argument so a user can raise it.
inline constexpr std::int64_t kDefaultMaxImagePixels = std::int64_t{1} << 28;

/// Writes a float image through OpenImageIO, atomically (temporary file + rename). The format
/// follows the extension: .exr as half float (linear values as they are); .png/.jpg/.tif as
/// 8 bits, each value v stored as round(255 * clamp(v, 0, 1)) (no transfer curve: encode first
/// if the values are linear radiance). 1, 3 or 4 channels. Throws InputError naming the file.
void write_image(const std::filesystem::path& file, const ImageF& image);
/// Writes an 8-bit image (1, 3 or 4 channels) through OpenImageIO, atomically; `jpeg_quality`
/// (1..100) is used for .jpg/.jpeg.
void write_image(const std::filesystem::path& file, const Image8& image, int jpeg_quality = 95);

}  // namespace meltlab
