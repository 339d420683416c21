#pragma once
// The one reader of YAML configs (kl fields, cameras, render scenes, observation manifests, the
// dataset catalog, reproduce configs), in the spirit of pbrt-v4's ParameterDictionary: a
// ConfigSection wraps one YAML mapping and hands out typed values by key, with defaults
// (`get<double>("eta", 1.31)`), as required values (`require<std::string>("name")`), as
// optionals, in a range, as number lists and as nested sections. Every key it hands out counts
// as read; `finish()` then refuses any key present that was never read (a typo, a key of another
// variant), for the section and every section made from it. Explicit, not in a destructor, so
// the error is thrown where throwing is safe.
//
// Every error is an InputError of one line, "FILE:LINE: ...", LINE being the line of the value
// concerned (of the mapping for a missing key, of the key for an unknown one):
//   scene.yaml:12: 'ice.eta' must be in [1, 4] (got 5)
//   scene.yaml:10: ice: missing key 'eta'
//   scene.yaml:11: ice: unknown key 'cx' (allowed: ca, cd, ...)
// A value's path ("ice.eta", "lights[1].colour", "kl.of[0]") names it in messages; a section's
// path is "" for a document's root. yaml-cpp's BadConversion never escapes: a value that does not
// convert is an InputError naming it. Duplicate keys in a mapping are refused.

#include <meltlab/core/error.h>

#include <Eigen/Core>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace meltlab {

class ConfigSection;

namespace config_detail {
struct SectionState;
}

/// Reads a YAML file through read_text_file (existence, size limit), parsing it with
/// parse_yaml_text. `kind` names the file in messages ("kl field", "scene").
YAML::Node load_yaml_file(const std::filesystem::path& file, std::string_view kind);

/// Parses YAML text read from `file`; a syntax error is the InputError "FILE:LINE: WHAT: MSG".
YAML::Node parse_yaml_text(const std::string& text, const std::string& file,
                           const std::string& what = "YAML syntax error");

/// load_yaml_file, as a section: the document must be a mapping.
ConfigSection load_config(const std::filesystem::path& file, std::string_view kind);

/// One value of a config: a YAML node, the file it came from and its path in the document.
/// Sections made from it (section(), items()...) are checked by the finish() of the section that
/// handed it out, or by its own finish() for a value made directly from a node.
class ConfigValue {
 public:
  /// A value read outside any section (e.g. a document's root): `file` names it in messages,
  /// `path` is how messages call it ("" for the document itself).
  ConfigValue(YAML::Node node, std::string file, std::string path = {});

  bool is_null() const { return node_.IsNull(); }
  bool is_scalar() const { return node_.IsScalar(); }
  bool is_sequence() const { return node_.IsSequence(); }
  bool is_map() const { return node_.IsMap(); }
  /// The scalar text ("" unless is_scalar()).
  std::string scalar() const { return node_.IsScalar() ? node_.Scalar() : std::string(); }

  const std::string& file() const;
  const std::string& path() const { return path_; }
  /// 1-based line of the value; 0 when yaml-cpp knows none (an empty document).
  int line() const { return line_; }
  /// "FILE:LINE" (or "FILE" when the line is unknown).
  std::string where() const;
  /// Throws "FILE:LINE: PATH: problem" ("FILE:LINE: problem" for an unnamed value).
  [[noreturn]] void fail(const std::string& problem) const;

  /// The value as T: double (finite), int, std::int64_t, bool or std::string (a scalar). Throws
  /// "FILE:LINE: 'PATH' must be a number (got 'abc')" and the like.
  template <class T>
  T as() const;
  /// as<T>() within [lo, hi]: "'PATH' must be in [lo, hi] (got x)".
  template <class T>
  T as_in_range(T lo, T hi) const;
  /// A list of n_min..n_max finite numbers; a list of lists is read row by row (a 4x4 matrix
  /// as 4 rows, or 16 numbers in one list).
  std::vector<double> as_numbers(std::size_t n_min, std::size_t n_max) const;
  /// Exactly 3 finite numbers, not nested: "'PATH' must be a list of 3 numbers".
  Eigen::Vector3d as_vec3() const;

  /// The elements of a sequence ("'PATH' must be a list" otherwise), named PATH[i].
  std::vector<ConfigValue> items() const;
  /// This mapping as a section ("PATH: must be a mapping" otherwise).
  ConfigSection section() const;

  /// Checks (as ConfigSection::finish) every section made from this value. Only for a value made
  /// directly from a node; a value handed out by a section is checked by that section's finish().
  void finish() const;

 private:
  friend class ConfigSection;
  ConfigValue(YAML::Node node, std::shared_ptr<config_detail::SectionState> owner, std::string path, int fallback_line);
  [[noreturn]] void fail_value(const std::string& problem) const;

  YAML::Node node_;
  std::shared_ptr<config_detail::SectionState> owner_;  ///< where sections made from this are registered
  std::string path_;
  int line_ = 0;
};

template <>
double ConfigValue::as<double>() const;
template <>
int ConfigValue::as<int>() const;
template <>
std::int64_t ConfigValue::as<std::int64_t>() const;
template <>
bool ConfigValue::as<bool>() const;
template <>
std::string ConfigValue::as<std::string>() const;
extern template double ConfigValue::as_in_range<double>(double, double) const;
extern template int ConfigValue::as_in_range<int>(int, int) const;
extern template std::int64_t ConfigValue::as_in_range<std::int64_t>(std::int64_t, std::int64_t) const;

/// One YAML mapping of a config: typed values by key, each key read counting as used. A
/// ConfigSection is a handle: copies share what has been read.
class ConfigSection {
 public:
  /// The mapping `node` read from `file`; `path` names it in messages ("" for a document root).
  ConfigSection(YAML::Node node, std::string file, std::string path = {});

  const std::string& file() const;
  const std::string& path() const;
  int line() const;
  std::string where() const;
  /// Throws "FILE:LINE: PATH: problem" at the mapping's line.
  [[noreturn]] void fail(const std::string& problem) const;
  /// Throws "FILE:LINE: PATH: problem" at the line of `key`'s value (the mapping's line if absent).
  [[noreturn]] void fail_at(const std::string& key, const std::string& problem) const;

  /// Whether `key` is present. Makes the key known (it is listed as allowed in messages) without
  /// counting it as read.
  bool has(const std::string& key) const;
  /// The keys present, in the file's order (for free-form mappings).
  std::vector<std::string> keys() const;
  /// Counts `key` as read without reading it (a value this variant deliberately ignores).
  void ignore(const std::string& key) const;

  /// The value of `key` ("missing key 'KEY'" when absent); counts as read.
  ConfigValue value(const std::string& key) const;
  std::optional<ConfigValue> optional_value(const std::string& key) const;

  template <class T>
  T require(const std::string& key) const {
    return value(key).as<T>();
  }
  template <class T>
  T get(const std::string& key, const T& fallback) const {
    const auto v = optional_value(key);
    return v ? v->as<T>() : fallback;
  }
  template <class T>
  std::optional<T> optional(const std::string& key) const {
    const auto v = optional_value(key);
    return v ? std::optional<T>(v->as<T>()) : std::nullopt;
  }
  template <class T>
  T require_in_range(const std::string& key, T lo, T hi) const {
    return value(key).as_in_range<T>(lo, hi);
  }
  template <class T>
  T get_in_range(const std::string& key, T fallback, T lo, T hi) const {
    const auto v = optional_value(key);
    return v ? v->as_in_range<T>(lo, hi) : fallback;
  }
  /// A finite number > 0: "'PATH' must be > 0 (got x)".
  double require_positive(const std::string& key) const;
  /// One of `options` (a scalar): "'PATH' must be one of a, b (got 'c')".
  std::string get_choice(const std::string& key, const std::string& fallback,
                         const std::vector<std::string>& options) const;
  Eigen::Vector3d require_vec3(const std::string& key) const { return value(key).as_vec3(); }
  Eigen::Vector3d get_vec3(const std::string& key, const Eigen::Vector3d& fallback) const {
    const auto v = optional_value(key);
    return v ? v->as_vec3() : fallback;
  }
  std::vector<double> require_numbers(const std::string& key, std::size_t n_min, std::size_t n_max) const {
    return value(key).as_numbers(n_min, n_max);
  }

  /// The mapping under `key`, as a section checked by this section's finish().
  ConfigSection section(const std::string& key) const { return value(key).section(); }
  std::optional<ConfigSection> optional_section(const std::string& key) const;
  /// The list of mappings under `key` (each named KEY[i]).
  std::vector<ConfigSection> sections(const std::string& key) const;

  /// Refuses the first key present but not read, here and in every section made from this one:
  /// "FILE:LINE: PATH: unknown key 'K' (allowed: ...)" for a key never asked for, "... key 'K' is
  /// not used here" for one asked for (has()) but not read. Call once everything is read.
  void finish() const;

 private:
  friend class ConfigValue;
  explicit ConfigSection(std::shared_ptr<config_detail::SectionState> state) : s_(std::move(state)) {}
  std::shared_ptr<config_detail::SectionState> s_;
};

}  // namespace meltlab
