#pragma once
// Shared by the fuzz targets (tests/fuzz/fuzz_*.cpp). A target hands the input bytes to one of
// meltlab's readers through a file (the readers take paths, as users give them) and accepts
// exactly one kind of failure: InputError, the one-line refusal of bad input. Anything else --
// another exception, a crash, a sanitizer report, an allocation beyond libFuzzer's
// -malloc_limit_mb, a hang -- is a finding.

#include <meltlab/core/error.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace meltlab::fuzz {

/// A private folder for this process's input files (in memory when /dev/shm exists).
inline const std::filesystem::path& work_dir() {
  static const std::filesystem::path dir = [] {
    std::error_code ec;
    const std::filesystem::path base = std::filesystem::is_directory("/dev/shm", ec) ? "/dev/shm" : "/tmp";
    auto d = base / ("meltlab-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

/// Writes the input to `name` inside work_dir() and returns its path.
inline std::filesystem::path write_input(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const auto path = work_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

/// Runs `read`; InputError is the expected refusal, anything else aborts (a finding).
template <class F>
int expect_only_input_errors(const char* target, F&& read) {
  try {
    read();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    // A refusal is one line.
    if (msg.find('\n') != std::string::npos) {
      std::fprintf(stderr, "%s: InputError spans several lines: %s\n", target, msg.c_str());
      std::abort();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: unexpected exception (not InputError): %s\n", target, e.what());
    std::abort();
  }
  return 0;
}

}  // namespace meltlab::fuzz
