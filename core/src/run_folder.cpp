#include <meltlab/core/error.h>
#include <meltlab/core/run_folder.h>

#include <fmt/format.h>
#include <unistd.h>

#include <system_error>

namespace meltlab {

namespace fs = std::filesystem;

std::string output_error_message(const std::string& what, const fs::path& path, const std::string& action,
                                 const std::error_code& ec) {
  return fmt::format("{} {}: cannot {}: {}", what, path.string(), action, ec.message());
}

void create_output_directories(const fs::path& dir, const std::string& what) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(output_error_message(what, dir, "create the folder", ec));
}

namespace {

bool is_empty_folder(const fs::path& dir) {
  std::error_code ec;
  return fs::directory_iterator(dir, ec) == fs::directory_iterator();
}

}  // namespace

RunFolder::RunFolder(fs::path target, RunFolderOptions options)
    : target_(std::move(target)), options_(std::move(options)) {
  const std::string& opt = options_.option;
  if (target_.empty()) throw InputError(fmt::format("{}: an output folder is required", opt));
  // "runs/a/" names the folder "a": drop a trailing separator so the staging name is a sibling.
  if (!target_.has_filename()) target_ = target_.parent_path();
  std::error_code ec;
  const fs::file_status st = fs::status(target_, ec);
  if (ec && ec != std::errc::no_such_file_or_directory)
    throw InputError(output_error_message(opt, target_, "use this path", ec));
  if (fs::exists(st)) {
    if (!fs::is_directory(st))
      throw InputError(fmt::format("{} {}: exists and is not a folder", opt, target_.string()));
    const bool holds_run = !options_.marker.empty() && fs::exists(target_ / options_.marker, ec);
    if (holds_run && !options_.overwrite)
      throw InputError(fmt::format("{} {}: already holds a {} ({}); choose another {} or pass --overwrite", opt,
                                   target_.string(), options_.kind, options_.marker, opt));
    if (!holds_run && !is_empty_folder(target_))
      throw InputError(
          fmt::format("{} {}: the folder is not empty and holds no previous {} ({}); choose an empty or "
                      "new folder",
                      opt, target_.string(), options_.kind, options_.marker));
  }
  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  // Remember the first folder of the chain that this run creates, to remove it again if the run
  // does not finish (nothing is left behind).
  for (fs::path p = parent; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) created_root_ = p;
  create_output_directories(parent, opt);
  staging_ = parent / fmt::format(".{}.partial-{}", target_.filename().string(), ::getpid());
  fs::remove_all(staging_, ec);  // a leftover of an earlier process with the same pid
  fs::create_directory(staging_, ec);
  if (ec) throw InputError(output_error_message(opt, target_, "create the folder", ec));
}

RunFolder::RunFolder(RunFolder&& other) noexcept
    : target_(std::move(other.target_)),
      staging_(std::move(other.staging_)),
      created_root_(std::move(other.created_root_)),
      options_(std::move(other.options_)),
      committed_(other.committed_) {
  other.committed_ = true;  // the moved-from folder owns nothing
}

RunFolder::~RunFolder() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!created_root_.empty()) fs::remove_all(created_root_, ec);
}

void RunFolder::commit() {
  if (committed_) return;
  std::error_code ec;
  fs::path old;
  if (fs::exists(target_, ec)) {  // an empty folder, or a previous run being overwritten
    old = target_.parent_path() / fmt::format(".{}.old-{}", target_.filename().string(), ::getpid());
    fs::remove_all(old, ec);
    fs::rename(target_, old, ec);
    if (ec) throw InputError(output_error_message(options_.option, target_, "replace the folder", ec));
  }
  fs::rename(staging_, target_, ec);
  if (ec) {
    std::error_code ignored;
    if (!old.empty()) fs::rename(old, target_, ignored);
    throw InputError(output_error_message(options_.option, target_, "move the finished run into place", ec));
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

}  // namespace meltlab
