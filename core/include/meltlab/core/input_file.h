#pragma once
// Opening an input file the same way everywhere: one line naming the file and the problem
// when it is missing, a folder, not a regular file, unreadable, empty or too large.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace meltlab {

/// Checks that `file` exists, is a regular file (or a link to one), can be opened and is not
/// empty; returns its size in bytes. `kind` names what the file should be ("mesh", "image",
/// "YAML config"), for the messages. Throws InputError.
std::int64_t check_input_file(const std::filesystem::path& file, std::string_view kind);

/// Reads a whole text input (config, manifest, CSV) after check_input_file, refusing files larger
/// than input_limits().text_bytes. Throws InputError naming the file.
std::string read_text_file(const std::filesystem::path& file, std::string_view kind);

}  // namespace meltlab
