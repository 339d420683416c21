#pragma once
// Small pieces of the line-oriented header readers (VLB, NRRD): whitespace fields and whole-field
// numbers. Each answers nullopt rather than throwing, so the reader names file:line itself.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace meltlab {

/// `s` without leading blanks/tabs and trailing blanks/tabs/CR.
std::string trim_blanks(std::string_view s);
/// The fields of a line separated by runs of blanks or tabs (no empty fields).
std::vector<std::string> blank_separated_fields(std::string_view line);
/// The finite number the whole of `s` spells (strtod), or nullopt (empty, trailing text,
/// out of range, inf/nan).
std::optional<double> parse_finite(const std::string& s);
/// The decimal integer the whole of `s` spells (optional '-', at most 12 characters) within
/// [lo, hi], or nullopt.
std::optional<std::int64_t> parse_whole(const std::string& s, std::int64_t lo, std::int64_t hi);

}  // namespace meltlab
