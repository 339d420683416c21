#pragma once
// The run folder: where one subcommand run (`simulate`, `compare`, `fit`, `render`,
// `synth-sequence`, `manufacture`, ...) writes its outputs. The protocol:
//  1. create() checks `--out` before any work is done: a file in the way, a folder that already
//     holds a finished run of this kind (its marker file) without --overwrite, or a folder that
//     holds other things, are refused; then it creates a staging folder beside the target
//     ("<parent>/.<name>.partial-<pid>"), so a path the file system refuses (a name too long, no
//     permission, a read-only disk, a file where a folder should be) fails at once with one
//     sentence naming the option (InputError, exit code 2), never with a raw library message.
//  2. The run writes into path() (the staging folder), each file atomically.
//  3. commit() renames the staging folder to the target (replacing the previous run when
//     overwriting), so `--out` either holds a complete run or nothing. A run that fails (an
//     exception) removes its staging folder; a killed run leaves only the hidden staging folder.

#include <filesystem>
#include <string>

namespace meltlab {

struct RunFolderOptions {
  std::string option = "--out";  ///< how the user named the folder (for messages)
  std::string marker;            ///< the file a finished run of this kind holds ("run.json")
  std::string kind = "run";      ///< what such a run is called ("run", "fit", "comparison")
  bool overwrite = false;        ///< replace a folder that holds a finished run (its marker)
};

class RunFolder {
 public:
  /// Checks `target` and creates the staging folder (see the protocol above). Throws InputError.
  RunFolder(std::filesystem::path target, RunFolderOptions options);
  RunFolder(RunFolder&& other) noexcept;
  RunFolder& operator=(RunFolder&&) = delete;
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;
  /// Removes the staging folder unless the run was committed.
  ~RunFolder();

  /// Where the run writes (the staging folder until commit, the target after it).
  const std::filesystem::path& path() const { return committed_ ? target_ : staging_; }
  /// The folder the user named.
  const std::filesystem::path& target() const { return target_; }
  /// The record file a finished run of this kind holds ("run.json", "fit.json").
  const std::string& marker() const { return options_.marker; }
  /// Moves the finished run into place. Throws InputError if the file system refuses.
  void commit();

 private:
  std::filesystem::path target_, staging_;
  std::filesystem::path created_root_;  ///< the first parent folder this run created, if any
  RunFolderOptions options_;
  bool committed_ = false;
};

/// One sentence for a file-system error on an output: "<what> <path>: cannot <action>: <reason>"
/// (the reason in words: "File name too long", "Permission denied", "No space left on device").
std::string output_error_message(const std::string& what, const std::filesystem::path& path, const std::string& action,
                                 const std::error_code& ec);

/// create_directories with the error as an InputError naming `what` (an option or a role).
void create_output_directories(const std::filesystem::path& dir, const std::string& what);

}  // namespace meltlab
