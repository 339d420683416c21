// A read-only shared memory map of a file (see core/mapped_file.h).

#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/mapped_file.h>

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace meltlab {

std::shared_ptr<const MappedFile> MappedFile::open(const std::filesystem::path& file, std::string_view kind) {
  check_input_file(file, kind);
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(fmt::format("{}: cannot open: {}", file.string(), std::strerror(errno)));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int e = errno;
    ::close(fd);
    throw InputError(fmt::format("{}: cannot stat: {}", file.string(), std::strerror(e)));
  }
  void* p = ::mmap(nullptr, std::size_t(st.st_size), PROT_READ, MAP_SHARED, fd, 0);
  const int e = errno;
  ::close(fd);  // the mapping keeps the file open
  if (p == MAP_FAILED) throw InputError(fmt::format("{}: cannot map the file: {}", file.string(), std::strerror(e)));
  std::shared_ptr<MappedFile> m(new MappedFile());
  m->path_ = file;
  m->data_ = static_cast<const std::uint8_t*>(p);
  m->size_ = std::int64_t(st.st_size);
  return m;
}

MappedFile::~MappedFile() {
  if (data_) ::munmap(const_cast<std::uint8_t*>(data_), std::size_t(size_));
}

void MappedFile::advise(Advice advice) const {
  int a = MADV_NORMAL;
  switch (advice) {
    case Advice::kNormal:
      a = MADV_NORMAL;
      break;
    case Advice::kSequential:
      a = MADV_SEQUENTIAL;
      break;
    case Advice::kRandom:
      a = MADV_RANDOM;
      break;
    case Advice::kWillNeed:
      a = MADV_WILLNEED;
      break;
  }
  ::madvise(const_cast<std::uint8_t*>(data_), std::size_t(size_), a);  // advice only: failure is harmless
}

bool evict_from_page_cache(const std::filesystem::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  ::fdatasync(fd);
  const bool ok = ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED) == 0;
  ::close(fd);
  return ok;
}

}  // namespace meltlab
