#pragma once
// Refusing unknown keys of a YAML mapping (a typo in a config must not pass silently).
// Header-only: used by the .cpp files that already read YAML (kl fields, cameras, scenes).

#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <set>
#include <string>

namespace meltlab {

/// Throws InputError "AT: unknown key 'K' (allowed: a, b, ...)" for the first key of the
/// mapping `n` that is not in `allowed`.
inline void refuse_unknown_keys(const YAML::Node& n, const std::string& at, const std::set<std::string>& allowed) {
  for (auto it = n.begin(); it != n.end(); ++it) {
    const std::string k = it->first.as<std::string>();
    if (allowed.count(k)) continue;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    throw InputError(fmt::format("{}: unknown key '{}' (allowed: {})", at, k, list));
  }
}

/// The one-line InputError for a yaml-cpp exception while reading `file`: "FILE:LINE: WHAT: MSG"
/// (yaml-cpp throws syntax errors while parsing, and BadConversion from any `as<T>()`).
inline InputError yaml_error(const std::string& file, const YAML::Exception& e, const std::string& what = "invalid YAML") {
  const std::string where = e.mark.line >= 0 ? fmt::format("{}:{}", file, e.mark.line + 1) : file;
  return InputError(fmt::format("{}: {}: {}", where, what, one_line(e.msg)));
}

}  // namespace meltlab
