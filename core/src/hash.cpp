#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>

#include <fmt/format.h>

#include <array>
#include <fstream>

namespace meltlab {

ContentHash& ContentHash::add_field(std::string_view bytes) {
  add_bytes(bytes);
  return add_bytes(fmt::format("|{}|", bytes.size()));
}

ContentHash& ContentHash::add_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(fmt::format("{}: cannot open for reading", file.string()));
  std::array<char, 1 << 16> buf;
  while (in) {
    in.read(buf.data(), buf.size());
    add_bytes(std::string_view(buf.data(), static_cast<std::size_t>(in.gcount())));
  }
  if (in.bad()) throw InputError(fmt::format("{}: read error", file.string()));
  return *this;
}

std::string ContentHash::hex() const { return fmt::format("{:016x}", h_); }

std::string file_hash(const std::filesystem::path& file) { return ContentHash().add_file(file).hex(); }

std::string text_hash(std::string_view text) { return ContentHash().add_bytes(text).hex(); }

}  // namespace meltlab
