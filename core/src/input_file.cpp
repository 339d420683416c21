#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>

#include <fstream>
#include <system_error>

namespace meltlab {

namespace fs = std::filesystem;

std::int64_t check_input_file(const fs::path& file, std::string_view kind) {
  const std::string name = file.string();
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (ec || !fs::exists(st)) {
    if (ec && ec != std::errc::no_such_file_or_directory)
      throw InputError(fmt::format("{}: cannot read: {}", name, ec.message()));
    throw InputError(fmt::format("{}: no such file", name));
  }
  if (fs::is_directory(st)) {
    const bool vowel = !kind.empty() && std::string_view("aeiou").find(kind.front()) != std::string_view::npos;
    throw InputError(fmt::format("{}: is a folder, not {} {} file", name, vowel ? "an" : "a", kind));
  }
  if (!fs::is_regular_file(st))
    throw InputError(fmt::format("{}: not a regular file (a {} file is expected)", name, kind));
  const auto size = fs::file_size(file, ec);
  if (ec) throw InputError(fmt::format("{}: cannot read: {}", name, ec.message()));
  {
    std::ifstream probe(file, std::ios::binary);
    if (!probe) throw InputError(fmt::format("{}: cannot open for reading", name));
  }
  if (size == 0) throw InputError(fmt::format("{}: file is empty", name));
  return static_cast<std::int64_t>(size);
}

std::string read_text_file(const fs::path& file, std::string_view kind) {
  const std::int64_t size = check_input_file(file, kind);
  const std::int64_t limit = input_limits().text_bytes;
  if (size > limit)
    throw InputError(
        fmt::format("{}: {} file of {} bytes exceeds the limit of {} (raise it with --limits text_bytes=N)",
                    file.string(), kind, size, limit));
  std::ifstream in(file, std::ios::binary);
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  if (!in && !in.eof()) throw InputError(fmt::format("{}: read error", file.string()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}

}  // namespace meltlab
