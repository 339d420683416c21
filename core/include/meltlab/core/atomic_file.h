#pragma once
// Atomic output: write to a temporary file beside the target, then rename over it, so a
// reader (or a killed run) never sees a half-written file.

#include <filesystem>
#include <functional>
#include <string>

namespace meltlab {

/// Path of the temporary file used for `target` (same folder, same extension, so tools
/// that pick the format from the extension still work): "<dir>/.<stem>.partial-<pid><ext>".
std::filesystem::path temporary_path_for(const std::filesystem::path& target);

/// Calls `write(tmp)` to produce the file at a temporary path, then renames it to `target`.
/// On any exception the temporary file is removed and the exception propagates.
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path&)>& write);

/// Writes `text` to `target` atomically.
void write_text_atomically(const std::filesystem::path& target, const std::string& text);

}  // namespace meltlab
