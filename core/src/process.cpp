#include <meltlab/core/error.h>
#include <meltlab/core/process.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <utility>

extern char** environ;

namespace meltlab {
namespace fs = std::filesystem;

namespace {

// A file descriptor closed when it goes out of scope.
class OwnedFd {
 public:
  OwnedFd() = default;
  explicit OwnedFd(int fd) : fd_(fd) {}
  OwnedFd(OwnedFd&& o) noexcept : fd_(std::exchange(o.fd_, -1)) {}
  OwnedFd& operator=(OwnedFd&& o) noexcept {
    reset();
    fd_ = std::exchange(o.fd_, -1);
    return *this;
  }
  OwnedFd(const OwnedFd&) = delete;
  OwnedFd& operator=(const OwnedFd&) = delete;
  ~OwnedFd() { reset(); }
  int get() const { return fd_; }

 private:
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  int fd_ = -1;
};

// Opened in the parent (close-on-exec), not by the spawn's file actions: a file that cannot
// be opened is then named in the error instead of passing for a program that cannot start.
// The descriptor is kept above 2 so that dup2 onto the standard stream always makes a fresh,
// inheritable copy (dup2 onto itself would keep close-on-exec).
OwnedFd open_redirection(const fs::path& file, int flags, const char* stream) {
  OwnedFd fd(::open(file.c_str(), flags | O_CLOEXEC, 0644));
  if (fd.get() < 0)
    throw InputError(
        fmt::format("{}: cannot open for the child's {}: {}", file.string(), stream, std::strerror(errno)));
  if (fd.get() <= STDERR_FILENO) {
    OwnedFd high(::fcntl(fd.get(), F_DUPFD_CLOEXEC, STDERR_FILENO + 1));
    if (high.get() < 0)
      throw InputError(
          fmt::format("{}: cannot open for the child's {}: {}", file.string(), stream, std::strerror(errno)));
    return high;
  }
  return fd;
}

// This process's environment with `additions` replacing or extending it, as NAME=value strings.
std::vector<std::string> child_environment(const std::vector<std::pair<std::string, std::string>>& additions) {
  std::vector<std::string> env;
  for (char** e = environ; e && *e; ++e) {
    const std::string entry(*e);
    const std::string name = entry.substr(0, entry.find('='));
    bool replaced = false;
    for (const auto& [k, v] : additions) replaced = replaced || k == name;
    if (!replaced) env.push_back(entry);
  }
  for (const auto& [k, v] : additions) env.push_back(k + "=" + v);
  return env;
}

std::vector<char*> c_strings(std::vector<std::string>& strings) {
  std::vector<char*> out;
  out.reserve(strings.size() + 1);
  for (auto& s : strings) out.push_back(s.data());
  out.push_back(nullptr);
  return out;
}

// posix_spawn_file_actions_t released when it goes out of scope.
class FileActions {
 public:
  FileActions() { posix_spawn_file_actions_init(&fa_); }
  ~FileActions() { posix_spawn_file_actions_destroy(&fa_); }
  FileActions(const FileActions&) = delete;
  FileActions& operator=(const FileActions&) = delete;
  void dup_onto(int fd, int stream) {
    if (const int rc = posix_spawn_file_actions_adddup2(&fa_, fd, stream); rc != 0)
      throw InvariantError(fmt::format("posix_spawn_file_actions_adddup2: {}", std::strerror(rc)));
  }
  const posix_spawn_file_actions_t* get() const { return &fa_; }

 private:
  posix_spawn_file_actions_t fa_;
};

}  // namespace

ProcessStatus run_process(const ProcessSpec& spec) {
  if (spec.argv.empty() || spec.argv[0].empty()) throw InvariantError("run_process: no program given");
  const std::string& program = spec.argv[0];
  FileActions actions;
  OwnedFd in, out, err;
  if (spec.stdin_file) {
    in = open_redirection(*spec.stdin_file, O_RDONLY, "stdin");
    actions.dup_onto(in.get(), STDIN_FILENO);
  }
  if (spec.stdout_file) {
    out = open_redirection(*spec.stdout_file, O_WRONLY | O_CREAT | O_TRUNC, "stdout");
    actions.dup_onto(out.get(), STDOUT_FILENO);
  }
  if (spec.stderr_file) {
    err = open_redirection(*spec.stderr_file, O_WRONLY | O_CREAT | O_TRUNC, "stderr");
    actions.dup_onto(err.get(), STDERR_FILENO);
  }
  std::vector<std::string> args = spec.argv;
  std::vector<char*> c_args = c_strings(args);
  std::vector<std::string> env = child_environment(spec.env_additions);
  std::vector<char*> c_env = c_strings(env);

  pid_t pid = 0;
  const int rc = spec.search_path
                     ? posix_spawnp(&pid, program.c_str(), actions.get(), nullptr, c_args.data(), c_env.data())
                     : posix_spawn(&pid, program.c_str(), actions.get(), nullptr, c_args.data(), c_env.data());
  if (rc != 0) throw InputError(fmt::format("cannot start '{}': {}", program, std::strerror(rc)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw InvariantError(fmt::format("waiting for '{}' failed: {}", program, std::strerror(errno)));
  ProcessStatus result;
  if (WIFEXITED(status)) result.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result.signal = WTERMSIG(status);
  return result;
}

}  // namespace meltlab
