#include <meltlab/core/error.h>
#include <meltlab/core/image_header.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <string>
#include <string_view>

namespace meltlab {

namespace {

std::uint32_t le32(const unsigned char* p) {
  return std::uint32_t(p[0]) | (std::uint32_t(p[1]) << 8) | (std::uint32_t(p[2]) << 16) | (std::uint32_t(p[3]) << 24);
}
std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | std::uint32_t(p[3]);
}

// OpenEXR: magic 76 2f 31 01, a 4-byte version, then attributes "name\0type\0" + int32 size + value,
// until an empty name. dataWindow is a box2i (xMin yMin xMax yMax, int32 each).
// An attribute that declares more bytes than the file holds is refused here: OpenEXR allocates
// the declared size before it notices (a fuzzed 460-byte file cost 1.6 GB).
std::optional<DeclaredImageSize> exr_size(const std::string& b, std::int64_t file_size, const std::string& file) {
  const auto* p = reinterpret_cast<const unsigned char*>(b.data());
  std::size_t at = 8;
  while (at < b.size()) {
    const std::size_t name_end = b.find('\0', at);
    if (name_end == std::string::npos) return std::nullopt;
    const std::string_view name(b.data() + at, name_end - at);
    if (name.empty()) return std::nullopt;  // end of the header without a dataWindow
    const std::size_t type_end = b.find('\0', name_end + 1);
    if (type_end == std::string::npos || type_end + 5 > b.size()) return std::nullopt;
    const std::uint32_t size = le32(p + type_end + 1);
    const std::size_t value = type_end + 5;
    if (static_cast<std::int64_t>(size) > file_size - static_cast<std::int64_t>(value))
      throw InputError(fmt::format(
          "{}: corrupt OpenEXR header: attribute '{}' declares {} bytes, more than the file holds", file, name, size));
    if (size > b.size() - value) return std::nullopt;  // beyond what we read: cannot say
    if (name == "dataWindow" && size == 16) {
      const auto x0 = static_cast<std::int32_t>(le32(p + value)), y0 = static_cast<std::int32_t>(le32(p + value + 4));
      const auto x1 = static_cast<std::int32_t>(le32(p + value + 8)),
                 y1 = static_cast<std::int32_t>(le32(p + value + 12));
      return DeclaredImageSize{std::int64_t{x1} - x0 + 1, std::int64_t{y1} - y0 + 1};
    }
    at = value + size;
  }
  return std::nullopt;
}

}  // namespace

std::optional<DeclaredImageSize> declared_image_size(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string b(1 << 16, '\0');
  in.read(b.data(), static_cast<std::streamsize>(b.size()));
  b.resize(static_cast<std::size_t>(in.gcount()));
  const auto* p = reinterpret_cast<const unsigned char*>(b.data());
  std::error_code ec;
  const auto file_size = static_cast<std::int64_t>(std::filesystem::file_size(file, ec));
  if (b.size() >= 8 && std::memcmp(p, "\x76\x2f\x31\x01", 4) == 0)
    return exr_size(b, ec ? 0 : file_size, file.string());
  if (b.size() >= 24 && std::memcmp(p, "\x89PNG\r\n\x1a\n", 8) == 0 && std::memcmp(p + 12, "IHDR", 4) == 0)
    return DeclaredImageSize{be32(p + 16), be32(p + 20)};
  return std::nullopt;
}

void check_declared_image_size(const std::filesystem::path& file) {
  check_declared_image_size(file, input_limits().image_pixels);
}

void check_declared_image_size(const std::filesystem::path& file, std::int64_t max_pixels) {
  const auto size = declared_image_size(file);
  if (!size) return;
  if (size->width <= 0 || size->height <= 0)
    throw InputError(
        fmt::format("{}: the header declares an image of {}x{} pixels", file.string(), size->width, size->height));
  const std::int64_t limit = max_pixels;
  if (size->width > limit || size->height > limit || size->width * size->height > limit)
    throw InputError(
        fmt::format("{}: the header declares {}x{} pixels, more than the limit of {} (raise it with "
                    "--limits image_pixels=N)",
                    file.string(), size->width, size->height, limit));
}

}  // namespace meltlab
