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
};

/// Width and height an OpenEXR or PNG file declares (EXR: the dataWindow attribute; PNG: the
/// IHDR chunk), or nullopt for other formats and for headers too broken to say (the image
/// library then refuses them). Reads at most the first 64 KiB. Throws InputError for an EXR
/// attribute that declares more bytes than the file holds.
std::optional<DeclaredImageSize> declared_image_size(const std::filesystem::path& file);

/// Throws InputError naming the file if the declared size exceeds input_limits().image_pixels
/// (or a side is not positive). Files whose size cannot be read from the header pass.
void check_declared_image_size(const std::filesystem::path& file);
/// The same against `max_pixels`.
void check_declared_image_size(const std::filesystem::path& file, std::int64_t max_pixels);

}  // namespace meltlab
