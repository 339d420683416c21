#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <unistd.h>

#include <fstream>
#include <system_error>

namespace meltlab {

std::filesystem::path temporary_path_for(const std::filesystem::path& target) {
  const auto dir = target.parent_path();
  const auto name = fmt::format(".{}.partial-{}{}", target.stem().string(), ::getpid(), target.extension().string());
  return dir.empty() ? std::filesystem::path(name) : dir / name;
}

void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path&)>& write) {
  const auto tmp = temporary_path_for(target);
  try {
    write(tmp);
    std::error_code ec;
    std::filesystem::rename(tmp, target, ec);
    if (ec) throw InputError(fmt::format("{}: cannot write: {}", target.string(), ec.message()));
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw;
  }
}

void write_text_atomically(const std::filesystem::path& target, const std::string& text) {
  write_atomically(target, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(fmt::format("{}: cannot open for writing", target.string()));
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) throw InputError(fmt::format("{}: write failed (disk full?)", target.string()));
  });
}

}  // namespace meltlab
