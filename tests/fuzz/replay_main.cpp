// Replays fuzz inputs through a target without libFuzzer: every file named on the command line,
// or found in a folder named there, is passed to LLVMFuzzerTestOneInput once. The default test
// suite runs it over the seed corpus and the regression inputs (a crash a fuzzer found, kept as
// a file once it is fixed), with GCC and under AddressSanitizer in `./scripts/test --asan`.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include <sys/resource.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

#if defined(__SANITIZE_ADDRESS__)
// Read by AddressSanitizer before ASAN_OPTIONS (which still overrides it). The fast unwinder
// stops at the first frame without a frame pointer (libstdc++), so a leak inside a library
// (OpenImageIO 2.4 keeps the message of a failed PNG read) would be recorded without the frame
// that tests/lsan.supp names, and reported. The replays allocate little, so the full unwinder
// costs nothing that matters here.
extern "C" const char* __asan_default_options() { return "fast_unwind_on_malloc=0"; }
#endif

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
#if !defined(__SANITIZE_ADDRESS__)
  // Address space capped as libFuzzer's -rss_limit_mb does, so an input that makes a reader
  // allocate without bound fails here too (AddressSanitizer reserves terabytes of address space
  // and has its own allocation checks, so the cap is left out under it).
  constexpr rlim_t kAddressSpaceBytes = rlim_t{3} << 30;
  const rlimit cap{kAddressSpaceBytes, kAddressSpaceBytes};
  setrlimit(RLIMIT_AS, &cap);
#endif
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path p = argv[i];
    if (fs::is_directory(p)) {
      for (const auto& e : fs::recursive_directory_iterator(p))
        if (e.is_regular_file()) files.push_back(e.path());
    } else if (fs::exists(p)) {
      files.push_back(p);
    }
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "replay %s (%zu bytes)\n", f.c_str(), bytes.size());
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("replayed %zu inputs\n", files.size());
  return files.empty() ? 1 : 0;
}
