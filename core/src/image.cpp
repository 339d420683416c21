#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/stderr_capture.h>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

namespace meltlab {

namespace fs = std::filesystem;

double sample_bilinear(const ImageF& image, double x, double y, int c, ImageWrap wrap_x, ImageWrap wrap_y) {
  const double fx0 = std::floor(x), fy0 = std::floor(y);
  const double fx = x - fx0, fy = y - fy0;
  // One modulo per axis; the neighbour wraps by a compare.
  auto indices = [](double f0, int n, ImageWrap wrap, int& k0, int& k1) {
    if (wrap == ImageWrap::kRepeat) {
      const long k = static_cast<long>(f0);
      k0 = static_cast<int>(((k % n) + n) % n);
      k1 = k0 + 1 == n ? 0 : k0 + 1;
    } else {
      k0 = std::clamp(static_cast<int>(f0), 0, n - 1);
      k1 = std::clamp(static_cast<int>(f0) + 1, 0, n - 1);
    }
  };
  int i0, i1, j0, j1;
  indices(fx0, image.width(), wrap_x, i0, i1);
  indices(fy0, image.height(), wrap_y, j0, j1);
  auto v = [&](int i, int j) { return static_cast<double>(image.at(i, j, c)); };
  return (1 - fy) * ((1 - fx) * v(i0, j0) + fx * v(i1, j0)) + fy * ((1 - fx) * v(i0, j1) + fx * v(i1, j1));
}

namespace {

std::string lower_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
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
  check_shape(file, image.width(), image.height(), image.channels());
  const std::string ext = lower_extension(file);
  if (ext == ".exr") {
    write_with_oiio(file, image.width(), image.height(), image.channels(), OIIO::TypeDesc::HALF, OIIO::TypeDesc::FLOAT,
                    image.data(), 0);
    return;
  }
  Image8 bytes(image.width(), image.height(), image.channels());
  for (std::size_t k = 0; k < image.size(); ++k)
    bytes.values()[k] =
        static_cast<std::uint8_t>(std::lround(std::clamp(static_cast<double>(image.values()[k]), 0.0, 1.0) * 255.0));
  write_image(file, bytes);
}

void write_image(const fs::path& file, const Image8& image, int jpeg_quality) {
  check_shape(file, image.width(), image.height(), image.channels());
  if (jpeg_quality < 1 || jpeg_quality > 100)
    throw InputError(fmt::format("{}: JPEG quality must be in [1, 100] (got {})", file.string(), jpeg_quality));
  write_with_oiio(file, image.width(), image.height(), image.channels(), OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8,
                  image.data(), jpeg_quality);
}

}  // namespace meltlab
