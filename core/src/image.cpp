#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/image_header.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/stderr_capture.h>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <string>

namespace meltlab {

namespace fs = std::filesystem;

namespace {

// Neighbour indices of a lookup along one axis of n pixels: k0 = floor(f0) addressed by
// `wrap`, k1 its right/lower neighbour. One modulo per axis; the neighbour wraps by a compare.
void neighbour_indices(double f0, int n, ImageWrap wrap, int& k0, int& k1) {
  if (wrap == ImageWrap::kRepeat) {
    const long k = static_cast<long>(f0);
    k0 = static_cast<int>(((k % n) + n) % n);
    k1 = k0 + 1 == n ? 0 : k0 + 1;
  } else {
    k0 = std::clamp(static_cast<int>(f0), 0, n - 1);
    k1 = std::clamp(static_cast<int>(f0) + 1, 0, n - 1);
  }
}

}  // namespace

double sample_bilinear(const ImageF& image, double x, double y, int c, ImageWrap wrap_x, ImageWrap wrap_y) {
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const double fx = x - fx0, fy = y - fy0;
  int i0, i1, j0, j1;
  neighbour_indices(fx0, image.width(), wrap_x, i0, i1);
  neighbour_indices(fy0, image.height(), wrap_y, j0, j1);
  auto v = [&](int i, int j) { return static_cast<double>(image.at(i, j, c)); };
  return (1 - fy) * ((1 - fx) * v(i0, j0) + fx * v(i1, j0)) + fy * ((1 - fx) * v(i0, j1) + fx * v(i1, j1));
}

Eigen::Vector3d sample_bilinear_rgb(const ImageF& image, double x, double y, ImageWrap wrap_x, ImageWrap wrap_y) {
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const double fx = x - fx0, fy = y - fy0;
  int i0, i1, j0, j1;
  neighbour_indices(fx0, image.width(), wrap_x, i0, i1);
  neighbour_indices(fy0, image.height(), wrap_y, j0, j1);
  Eigen::Vector3d out;
  for (int c = 0; c < 3; ++c) {
    auto v = [&](int i, int j) { return static_cast<double>(image.at(i, j, c)); };
    out[c] = (1 - fy) * ((1 - fx) * v(i0, j0) + fx * v(i1, j0)) + fy * ((1 - fx) * v(i0, j1) + fx * v(i1, j1));
  }
  return out;
}

namespace {

std::string lower_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  return ext;
}

void check_shape(const fs::path& file, int width, int height, int channels) {
  if (width <= 0 || height <= 0)
    throw InputError(fmt::format("{}: cannot write an empty image ({}x{})", file.string(), width, height));
  if (channels != 1 && channels != 3 && channels != 4)
    throw InputError(fmt::format("{}: cannot write a {}-channel image (1, 3 or 4 only)", file.string(), channels));
}

// Writes through OpenImageIO into a temporary file beside `file` and renames it.
void write_with_oiio(const fs::path& file, int width, int height, int channels, OIIO::TypeDesc file_type,
                     OIIO::TypeDesc data_type, const void* data, int jpeg_quality) {
  write_atomically(file, [&](const fs::path& tmp) {
    auto out = OIIO::ImageOutput::create(tmp.string());
    if (!out) throw InputError(fmt::format("{}: cannot write: {}", file.string(), one_line(OIIO::geterror())));
    OIIO::ImageSpec spec(width, height, channels, file_type);
    spec.attribute("oiio:UnassociatedAlpha", 1);
    // Without an (empty) Exif directory in TIFFs: OIIO 2.4 with Debian's libtiff reports a
    // spurious "failed TIFFWriteCustomDirectory() of the Exif data" error otherwise.
    spec.attribute("tiff:write_exif", 0);
    const std::string ext = lower_extension(file);
    if (ext == ".jpg" || ext == ".jpeg") {
      spec.attribute("Compression", fmt::format("jpeg:{}", jpeg_quality));
      spec.attribute("CompressionQuality", jpeg_quality);
    }
    bool ok = out->open(tmp.string(), spec);
    if (ok) ok = out->write_image(data_type, data);
    // close() also flushes; it must run (and be checked) even after a failed write.
    const bool closed = out->close();
    std::string err = out->geterror();
    const std::string global = OIIO::geterror();
    if (err.empty()) err = global;
    if (!ok || !closed || !err.empty())
      throw InputError(fmt::format("{}: cannot write: {}", file.string(), one_line(err)));
  });
}

}  // namespace

void write_image(const fs::path& file, const ImageF& image) {
  write_image(file, image, lower_extension(file) == ".exr" ? PixelFormat::kHalf : PixelFormat::kUint8);
}

void write_image(const fs::path& file, const ImageF& image, PixelFormat stored, int jpeg_quality) {
  check_shape(file, image.width(), image.height(), image.channels());
  switch (stored) {
    case PixelFormat::kHalf:
    case PixelFormat::kFloat:
      write_with_oiio(file, image.width(), image.height(), image.channels(),
                      stored == PixelFormat::kHalf ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT,
                      OIIO::TypeDesc::FLOAT, image.data(), jpeg_quality);
      return;
    case PixelFormat::kUint8: {
      Image8 bytes(image.width(), image.height(), image.channels());
      for (std::size_t k = 0; k < image.size(); ++k)
        bytes.values()[k] = static_cast<std::uint8_t>(
            std::lround(std::clamp(static_cast<double>(image.values()[k]), 0.0, 1.0) * 255.0));
      write_image(file, bytes, jpeg_quality);
      return;
    }
    case PixelFormat::kUint16: {
      std::vector<std::uint16_t> words(image.size());
      for (std::size_t k = 0; k < image.size(); ++k)
        words[k] = static_cast<std::uint16_t>(
            std::lround(std::clamp(static_cast<double>(image.values()[k]), 0.0, 1.0) * 65535.0));
      write_with_oiio(file, image.width(), image.height(), image.channels(), OIIO::TypeDesc::UINT16,
                      OIIO::TypeDesc::UINT16, words.data(), jpeg_quality);
      return;
    }
  }
}

void write_image(const fs::path& file, const Image8& image, int jpeg_quality) {
  check_shape(file, image.width(), image.height(), image.channels());
  if (jpeg_quality < 1 || jpeg_quality > 100)
    throw InputError(fmt::format("{}: JPEG quality must be in [1, 100] (got {})", file.string(), jpeg_quality));
  write_with_oiio(file, image.width(), image.height(), image.channels(), OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8,
                  image.data(), jpeg_quality);
}

// ---- reading ------------------------------------------------------------------------

namespace {

/// The first error pending in `in` or, failing that, in OpenImageIO's global state; both are
/// cleared (OpenImageIO complains about unretrieved errors later otherwise).
std::string pending_error(const OIIO::ImageInput* in) {
  std::string err = in ? in->geterror() : std::string();
  std::string global = OIIO::geterror();
  if (err.empty()) err = std::move(global);
  return err;
}

PixelFormat pixel_format_of(OIIO::TypeDesc type) {
  switch (type.basetype) {
    case OIIO::TypeDesc::UINT8:
    case OIIO::TypeDesc::INT8:
      return PixelFormat::kUint8;
    case OIIO::TypeDesc::UINT16:
    case OIIO::TypeDesc::INT16:
      return PixelFormat::kUint16;
    case OIIO::TypeDesc::HALF:
      return PixelFormat::kHalf;
    default:
      return PixelFormat::kFloat;
  }
}

// Checks `file` and opens it with OpenImageIO, validating the header.
std::unique_ptr<OIIO::ImageInput> open_image(const fs::path& file, std::int64_t max_pixels, ImageAlpha alpha) {
  const std::int64_t file_bytes = check_input_file(file, "image");
  check_declared_image_size(file, max_pixels);  // before OpenImageIO allocates anything from the header
  OIIO::ImageSpec config;
  if (alpha == ImageAlpha::kAsStored) config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(file.string(), &config);
  if (!in)
    throw InputError(fmt::format("{}: not a readable image: {}", file.string(), one_line(pending_error(nullptr))));
  const OIIO::ImageSpec& spec = in->spec();
  auto refuse = [&](const std::string& problem) {
    pending_error(in.get());
    throw InputError(fmt::format("{}: {}", file.string(), problem));
  };
  if (spec.width <= 0 || spec.height <= 0) refuse(fmt::format("image has zero size ({}x{})", spec.width, spec.height));
  const std::int64_t pixels = static_cast<std::int64_t>(spec.width) * spec.height;
  if (pixels > max_pixels)
    refuse(fmt::format("image of {}x{} = {} pixels exceeds the limit of {} (raise it with --limits image_pixels=N)",
                       spec.width, spec.height, pixels, max_pixels));
  if (spec.depth > 1 || spec.deep || spec.nchannels < 1 || spec.nchannels > 64)
    refuse(fmt::format("not a flat 2-D image (depth {}, {} channels{})", spec.depth, spec.nchannels,
                       spec.deep ? ", deep" : ""));
  // Every format's samples, whatever its header (BMP, TIFF, ... beyond the EXR/PNG pre-check),
  // must fit in the file at the best compression any image codec reaches: a fuzzed 250-byte BMP
  // declaring 8 x 16187400 pixels asked for 1.5 GB.
  const std::int64_t sample_bytes = checked_mul(pixels, std::int64_t(spec.pixel_bytes(true)));
  const std::int64_t room = checked_mul(file_bytes, kMaxImageCompressionRatio);
  if (sample_bytes < 0 || (room >= 0 && sample_bytes > room))
    refuse(fmt::format("corrupt or truncated image: {}x{} pixels of {} channels cannot fit in {} bytes", spec.width,
                       spec.height, spec.nchannels, file_bytes));
  return in;
}

}  // namespace

ImageFileInfo read_image_info(const fs::path& file, std::int64_t max_pixels) {
  const StderrCapture quiet;  // libpng prints its errors itself; ours is the one line
  auto in = open_image(file, max_pixels, ImageAlpha::kAsStored);
  const OIIO::ImageSpec& spec = in->spec();
  const ImageFileInfo info{spec.width, spec.height, spec.nchannels, pixel_format_of(spec.format)};
  in->close();
  pending_error(in.get());
  return info;
}

ImageF read_image(const fs::path& file, std::int64_t max_pixels, ImageAlpha alpha, PixelFormat* stored) {
  // OpenImageIO reports most problems through its error state rather than the return value (a
  // JPEG cut in half decodes "successfully" with grey filler and a pending "Premature end of
  // JPEG file"), so every call is followed by a check of the pending error.
  const StderrCapture quiet;  // libpng prints its errors itself; ours is the one line
  auto in = open_image(file, max_pixels, alpha);
  const OIIO::ImageSpec spec = in->spec();
  ImageF image(spec.width, spec.height, spec.nchannels);
  const bool ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.data());
  const std::string err = pending_error(in.get());
  in->close();
  const std::string close_err = pending_error(in.get());
  if (!ok || !err.empty() || !close_err.empty())
    throw InputError(
        fmt::format("{}: truncated or corrupt image: {}", file.string(), one_line(!err.empty() ? err : close_err)));
  if (stored) *stored = pixel_format_of(spec.format);
  return image;
}

}  // namespace meltlab
