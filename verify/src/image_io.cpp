// Image IO through OpenImageIO: photos in, masks and overlays out.
//
// OIIO reports most problems through its error state rather than the return value (a JPEG
// cut in half decodes "successfully" with grey filler and a pending "Premature end of JPEG
// file" error), so every call is followed by a check of geterror(); any pending error
// refuses the image.

#include "obs_detail.h"

#include <meltlab/core/image_header.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/limits.h>
#include <meltlab/core/stderr_capture.h>
#include <meltlab/verify/observations.h>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <cstdint>
#include <string>
#include <system_error>

namespace meltlab::verify {

namespace fs = std::filesystem;

namespace {

/// The first error pending in `in` or, failing that, in OIIO's global state; both are
/// cleared so that OIIO does not complain about unretrieved errors later.
std::string pending_error(const OIIO::ImageInput* in) {
  std::string err = in ? in->geterror() : std::string();
  std::string global = OIIO::geterror();
  if (err.empty()) err = std::move(global);
  return err;
}

/// Checks the file itself before OIIO sees it, for messages that say what is wrong.
void check_file(const fs::path& file) {
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (ec || !fs::exists(st)) throw InputError(fmt::format("{}: no such file", file.string()));
  if (fs::is_directory(st)) throw InputError(fmt::format("{}: is a directory, not an image", file.string()));
  if (!fs::is_regular_file(st)) throw InputError(fmt::format("{}: not a regular file", file.string()));
  const auto size = fs::file_size(file, ec);
  if (ec) throw InputError(fmt::format("{}: cannot read: {}", file.string(), ec.message()));
  if (size == 0) throw InputError(fmt::format("{}: empty file (0 bytes), not an image", file.string()));
}

/// Opens `file` with OIIO and validates its header.
std::unique_ptr<OIIO::ImageInput> open_image(const fs::path& file) {
  check_file(file);
  check_declared_image_size(file);  // before OpenImageIO allocates anything from the header
  // Colours as stored: no premultiplication by alpha (OIIO associates alpha by default).
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(file.string(), &config);
  if (!in) {
    throw InputError(
        fmt::format("{}: not a readable image: {}", file.string(), one_line(pending_error(nullptr))));
  }
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0) {
    pending_error(in.get());
    throw InputError(fmt::format("{}: image has zero size ({}x{})", file.string(), spec.width, spec.height));
  }
  // Larger images are refused: a corrupt or hostile header must not make us allocate gigabytes.
  const std::int64_t pixels = static_cast<std::int64_t>(spec.width) * spec.height;
  if (pixels > input_limits().image_pixels) {
    pending_error(in.get());
    throw InputError(fmt::format("{}: image of {}x{} = {} pixels exceeds the limit of {} (raise it with --limits "
                                 "image_pixels=N)",
                                 file.string(), spec.width, spec.height, pixels, input_limits().image_pixels));
  }
  if (spec.depth > 1 || spec.deep || spec.nchannels < 1 || spec.nchannels > 64) {
    pending_error(in.get());
    throw InputError(fmt::format("{}: not a flat 2-D image (depth {}, {} channels{})", file.string(), spec.depth,
                                 spec.nchannels, spec.deep ? ", deep" : ""));
  }
  return in;
}

}  // namespace

namespace detail {

cv::Size read_image_size(const fs::path& file) {
  const StderrCapture quiet;
  auto in = open_image(file);
  const cv::Size size(in->spec().width, in->spec().height);
  in->close();
  pending_error(in.get());
  return size;
}

}  // namespace detail

cv::Mat read_image(const fs::path& file) {
  const StderrCapture quiet;  // libpng prints its errors itself; ours is the one line
  auto in = open_image(file);
  const OIIO::ImageSpec spec = in->spec();

  // 8- and 16-bit integers are kept as they are (signed ones are read as unsigned, which
  // OIIO remaps); everything else (half, float, double, 32-bit ints) becomes float.
  OIIO::TypeDesc type = OIIO::TypeDesc::FLOAT;
  int depth = CV_32F;
  switch (spec.format.basetype) {
    case OIIO::TypeDesc::UINT8:
    case OIIO::TypeDesc::INT8:
      type = OIIO::TypeDesc::UINT8;
      depth = CV_8U;
      break;
    case OIIO::TypeDesc::UINT16:
    case OIIO::TypeDesc::INT16:
      type = OIIO::TypeDesc::UINT16;
      depth = CV_16U;
      break;
    default:
      break;
  }
  // 1 or 2 channels (grey, grey + alpha) -> grey; 3 or more (RGB, RGBA, ...) -> the first
  // three as colour. Alpha is dropped.
  const int channels = spec.nchannels >= 3 ? 3 : 1;
  cv::Mat image(spec.height, spec.width, CV_MAKETYPE(depth, channels));
  const bool ok = in->read_image(0, 0, 0, channels, type, image.data);
  const std::string err = pending_error(in.get());
  in->close();
  const std::string close_err = pending_error(in.get());
  if (!ok || !err.empty() || !close_err.empty()) {
    throw InputError(fmt::format("{}: truncated or corrupt image: {}", file.string(),
                                 one_line(!err.empty() ? err : close_err)));
  }
  if (channels == 3) cv::cvtColor(image, image, cv::COLOR_RGB2BGR);
  return image;
}

void write_image(const fs::path& file, const cv::Mat& image) {
  if (image.empty()) throw InputError(fmt::format("{}: cannot write an empty image", file.string()));
  OIIO::TypeDesc type;
  switch (image.depth()) {
    case CV_8U: type = OIIO::TypeDesc::UINT8; break;
    case CV_16U: type = OIIO::TypeDesc::UINT16; break;
    case CV_32F: type = OIIO::TypeDesc::FLOAT; break;
    default:
      throw InputError(fmt::format("{}: cannot write pixels of OpenCV depth {} (8U, 16U or 32F only)", file.string(),
                                   image.depth()));
  }
  const int channels = image.channels();
  if (channels != 1 && channels != 3 && channels != 4) {
    throw InputError(fmt::format("{}: cannot write a {}-channel image (1, 3 or 4 only)", file.string(), channels));
  }
  cv::Mat pixels;
  if (channels == 3) {
    cv::cvtColor(image, pixels, cv::COLOR_BGR2RGB);
  } else if (channels == 4) {
    cv::cvtColor(image, pixels, cv::COLOR_BGRA2RGBA);
  } else {
    pixels = image.isContinuous() ? image : image.clone();
  }

  write_atomically(file, [&](const fs::path& tmp) {
    auto out = OIIO::ImageOutput::create(tmp.string());
    if (!out) {
      throw InputError(fmt::format("{}: cannot write: {}", file.string(), one_line(OIIO::geterror())));
    }
    OIIO::ImageSpec spec(pixels.cols, pixels.rows, channels, type);
    // The pixels are written as given (alpha not associated), and without an (empty)
    // Exif directory in TIFFs: OIIO 2.4 with Debian's libtiff reports a spurious
    // "failed TIFFWriteCustomDirectory() of the Exif data" error otherwise.
    spec.attribute("oiio:UnassociatedAlpha", 1);
    spec.attribute("tiff:write_exif", 0);
    bool ok = out->open(tmp.string(), spec);
    if (ok) ok = out->write_image(type, pixels.data);
    // close() also flushes; it must run (and be checked) even after a failed write.
    const bool closed = out->close();
    std::string err = out->geterror();
    const std::string global = OIIO::geterror();
    if (err.empty()) err = global;
    if (!ok || !closed || !err.empty()) {
      throw InputError(fmt::format("{}: cannot write: {}", file.string(), one_line(err)));
    }
  });
}

}  // namespace meltlab::verify
