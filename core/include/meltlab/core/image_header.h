#pragma once
// The pixel size an image file declares, read from its header without an image library. Some
// readers allocate from the header when they open a file (OpenEXR reads a table with one entry
// per block of scanlines: a 400-byte file claiming 2^30 rows costs gigabytes before OpenImageIO
// returns), so the image readers check the declared size against input_limits().image_pixels
// BEFORE they hand the file to OpenImageIO.

#include <cstdint>
#include <filesystem>
#include <optional>

namespace meltlab {

struct DeclaredImageSize {
  std::int64_t width = 0, height = 0;
  /// Bytes of samples the header implies (width x height x bytes per pixel of the declared
  /// channels, or bits for PNG), 0 when unknown.
  std::int64_t sample_bytes = 0;
  /// Whether the samples may be compressed (false: an uncompressed EXR must hold them all).
  bool compressed = true;
};

/// The largest ratio of declared sample bytes to file bytes a header may claim: deflate, which
/// PNG and OpenEXR's ZIP use, packs at most ~1032:1 (a constant image); OpenEXR's other codecs
/// (RLE, PIZ, PXR24, B44, DWA) pack less. Twice deflate's bound: no real image comes near it, while
/// a fuzzed 662-byte EXR declaring 2752520 x 8 pixels made OpenImageIO allocate 4.2 GB.
inline constexpr std::int64_t kMaxImageCompressionRatio = 2048;

/// Width and height an OpenEXR or PNG file declares (EXR: the dataWindow attribute; PNG: the
/// IHDR chunk), or nullopt for other formats and for headers too broken to say (the image
/// library then refuses them). Reads at most the first 64 KiB. Throws InputError for an EXR
/// attribute that declares more bytes than the file holds.
std::optional<DeclaredImageSize> declared_image_size(const std::filesystem::path& file);

/// Throws InputError naming the file if the declared size exceeds input_limits().image_pixels
/// (or a side is not positive), or if the declared samples cannot fit in the file even at
/// kMaxImageCompressionRatio (or uncompressed, for an uncompressed EXR). Files whose size cannot
/// be read from the header pass.
void check_declared_image_size(const std::filesystem::path& file);
/// The same against `max_pixels`.
void check_declared_image_size(const std::filesystem::path& file, std::int64_t max_pixels);

}  // namespace meltlab
