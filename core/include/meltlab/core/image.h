#pragma once
// The one image type of meltlab: a width x height grid of pixels with `channels` values each,
// interleaved, row-major, row 0 at the top. Pixel convention as in render/camera.h: x grows to
// the right, y downwards, integer coordinates are pixel CENTRES.
//
// Colour images are RGB (OpenImageIO's order) unless a function says otherwise; OpenCV's BGR
// cv::Mat stays inside verify/ and the photo renderer, converted at that edge.
// Values: float images are linear radiance or any scalar field; 8-bit images are encoded
// display values 0..255.

#include <meltlab/core/limits.h>

#include <Eigen/Core>

#include <algorithm>

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
      : width_(width),
        height_(height),
        channels_(channels),
        data_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * static_cast<std::size_t>(channels),
              fill) {}

  /// Makes this a width x height x channels image. An image of that shape already keeps its
  /// storage and values (a caller that writes every value reuses it without new memory).
  void reshape(int width, int height, int channels) {
    if (width != width_ || height != height_ || channels != channels_) *this = Image(width, height, channels);
  }

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

/// sample_bilinear with clamping for a point already inside [0, width-1] x [0, height-1] (the
/// caller clamped it: tables whose coordinates come from a clamped node index), inline and
/// without the addressing: bitwise the same value (at x = width-1 it weighs the last two columns
/// 0 and 1, which is the last column exactly).
inline double sample_bilinear_inside(const ImageF& image, double x, double y, int c = 0) {
  const int i0 = image.width() > 1 ? std::min(static_cast<int>(x), image.width() - 2) : 0;
  const int j0 = image.height() > 1 ? std::min(static_cast<int>(y), image.height() - 2) : 0;
  const int i1 = image.width() > 1 ? i0 + 1 : 0, j1 = image.height() > 1 ? j0 + 1 : 0;
  const double fx = x - i0, fy = y - j0;
  auto v = [&](int i, int j) { return static_cast<double>(image.at(i, j, c)); };
  return (1 - fy) * ((1 - fx) * v(i0, j0) + fx * v(i1, j0)) + fy * ((1 - fx) * v(i0, j1) + fx * v(i1, j1));
}

/// Bilinear lookup of channels 0..2 at (x, y), as sample_bilinear per channel (bitwise the
/// same values) with the neighbour indices computed once: the renderer's texture lookups.
Eigen::Vector3d sample_bilinear_rgb(const ImageF& image, double x, double y, ImageWrap wrap_x, ImageWrap wrap_y);

/// How an image file stores its values (what read_image converted from, what write_image
/// converts to). Integer files map 0..max to 0..1.
enum class PixelFormat {
  kUint8,   ///< 8 bits (also for signed 8-bit files, remapped by OpenImageIO)
  kUint16,  ///< 16 bits (also for signed 16-bit files)
  kHalf,    ///< 16-bit float (OpenEXR's default)
  kFloat,   ///< 32-bit float (and anything wider: doubles, 32-bit integers)
};

/// Whether read_image leaves colours as stored or multiplies them by alpha.
enum class ImageAlpha {
  kAsStored,    ///< colours as the file stores them (no premultiplication)
  kAssociated,  ///< OpenImageIO's default: colours multiplied by alpha for files with unassociated alpha
};

/// Reads any image OpenImageIO reads (EXR, HDR, PNG, JPEG, TIFF, ...) as float, all channels
/// as stored (8- and 16-bit values normalised to [0, 1], no colour transform). Checks the file
/// (check_input_file) and the size its header declares (check_declared_image_size) BEFORE
/// OpenImageIO allocates anything, then the opened size against `max_pixels`; a truncated or
/// corrupt file is refused, also when OpenImageIO only reports it as a pending error. If
/// `stored` is given it receives the file's value format. Throws a one-line InputError
/// "<file>: <problem>".
ImageF read_image(const std::filesystem::path& file, std::int64_t max_pixels = input_limits().image_pixels,
                  ImageAlpha alpha = ImageAlpha::kAsStored, PixelFormat* stored = nullptr);

struct ImageFileInfo {
  int width = 0, height = 0, channels = 0;
  PixelFormat format = PixelFormat::kUint8;
};
/// The size, channels and value format of an image file from its header, with read_image's
/// checks and errors (the pixels are not decoded).
ImageFileInfo read_image_info(const std::filesystem::path& file, std::int64_t max_pixels = input_limits().image_pixels);

/// Writes a float image through OpenImageIO, atomically (temporary file + rename). The format
/// follows the extension: .exr as half float (linear values as they are); .png/.jpg/.tif as
/// 8 bits, each value v stored as round(255 * clamp(v, 0, 1)) (no transfer curve: encode first
/// if the values are linear radiance). 1, 3 or 4 channels. Throws InputError naming the file.
void write_image(const std::filesystem::path& file, const ImageF& image);
/// The same with the stored format given: kUint8/kUint16 store round(max * clamp(v, 0, 1)),
/// kHalf/kFloat the values (for formats that hold floats: EXR, TIFF); `jpeg_quality` as below.
void write_image(const std::filesystem::path& file, const ImageF& image, PixelFormat stored, int jpeg_quality = 95);
/// Writes an 8-bit image (1, 3 or 4 channels) through OpenImageIO, atomically; `jpeg_quality`
/// (1..100) is used for .jpg/.jpeg.
void write_image(const std::filesystem::path& file, const Image8& image, int jpeg_quality = 95);

}  // namespace meltlab
