#pragma once
// Running a child program (tar for the CGAL archive, meltlab and python steps of `reproduce`):
// no shell, so arguments are never re-parsed; standard streams optionally redirected to files
// (or /dev/null); the environment inherited, with additions.

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace meltlab {

/// The null device, for a redirection that discards output or gives an empty input.
inline const std::filesystem::path kNullDevice = "/dev/null";

struct ProcessSpec {
  std::vector<std::string> argv;  ///< argv[0] is the program; must not be empty
  bool search_path = true;        ///< look argv[0] up in PATH (as a shell would) unless it holds a '/'
  /// Redirections: unset inherits this process's stream. stdin is opened for reading; stdout
  /// and stderr are created or truncated (mode 0644), each by its own open, so give them
  /// distinct files (kNullDevice excepted).
  std::optional<std::filesystem::path> stdin_file, stdout_file, stderr_file;
  /// Variables added to (or replacing those of) this process's environment.
  std::vector<std::pair<std::string, std::string>> env_additions;
};

struct ProcessStatus {
  int exit_code = -1;  ///< the exit status if the program exited, else -1
  int signal = 0;      ///< the signal that ended it, else 0
  bool exited_ok() const { return signal == 0 && exit_code == 0; }
  /// The status as a shell reports it: the exit status, or 128 + the signal number.
  int shell_status() const { return signal != 0 ? 128 + signal : exit_code; }
};

/// Starts the program and waits for it (waitpid retried on EINTR). Throws InputError
/// ("cannot start 'prog': No such file or directory", or naming the redirection file that
/// cannot be opened) when the program cannot be started; InvariantError if waiting fails.
ProcessStatus run_process(const ProcessSpec& spec);

}  // namespace meltlab
