#pragma once
// A read-only, shared memory map of a whole file (POSIX mmap, MAP_SHARED, PROT_READ): large
// volumes are read in place and shared by every thread; the pages come from the page cache, so a
// file larger than RAM can be read. The map is held through a shared owner, so a Volume that
// views part of it keeps it alive.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>

namespace meltlab {

class MappedFile {
 public:
  /// Maps `file` (after check_input_file: exists, regular, readable, not empty). Throws
  /// InputError naming the file when it cannot be opened or mapped.
  static std::shared_ptr<const MappedFile> open(const std::filesystem::path& file, std::string_view kind);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const std::uint8_t* data() const { return data_; }
  std::int64_t size() const { return size_; }
  const std::filesystem::path& path() const { return path_; }

  /// Advice for the kernel's read-ahead (madvise): kSequential before a scan, kRandom for ray
  /// casting, kWillNeed to start reading the whole file in.
  enum class Advice { kNormal, kSequential, kRandom, kWillNeed };
  void advise(Advice advice) const;

 private:
  MappedFile() = default;
  std::filesystem::path path_;
  const std::uint8_t* data_ = nullptr;
  std::int64_t size_ = 0;
};

/// Drops the file's clean pages from the page cache (posix_fadvise DONTNEED), so that the next
/// read of it comes from the disk: a cold-cache measurement without root and without touching
/// other files. Pages still mapped by a live MappedFile may stay. Returns false if the kernel
/// refused.
bool evict_from_page_cache(const std::filesystem::path& file);

}  // namespace meltlab
