// The one YAML config reader (config.h).

#include <meltlab/core/config.h>
#include <meltlab/core/input_file.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace meltlab {

namespace config_detail {

/// What a section (or the holder of a free-standing value) knows: its mapping, which keys were
/// asked for and read, and the sections made from it (checked by its finish()).
struct SectionState {
  YAML::Node node;  ///< the mapping; undefined for the holder of a free-standing value
  std::shared_ptr<const std::string> file;
  std::string path;
  int line = 0;                    ///< 1-based; 0 unknown
  bool is_section = false;         ///< false: only a holder of sections made from a free-standing value
  std::vector<std::string> asked;  ///< keys asked for (present or not), in order
  std::set<std::string> read;
  std::vector<std::shared_ptr<SectionState>> children;

  void ask(const std::string& key) {
    if (std::find(asked.begin(), asked.end(), key) == asked.end()) asked.push_back(key);
  }
};

}  // namespace config_detail

using config_detail::SectionState;

namespace {

std::string where_of(const std::string& file, int line) { return line > 0 ? fmt::format("{}:{}", file, line) : file; }

int line_of(const YAML::Node& n, int fallback) {
  const YAML::Mark m = n.Mark();
  return m.line >= 0 ? m.line + 1 : fallback;
}

std::string join(const std::vector<std::string>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + i;
  return s;
}

/// What a value is, for "(got ...)" in messages.
std::string got(const YAML::Node& n) {
  if (n.IsScalar()) return fmt::format("'{}'", n.Scalar());
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a mapping";
  return "nothing";
}

[[noreturn]] void throw_at(const std::string& file, int line, const std::string& path, const std::string& problem) {
  if (path.empty()) throw InputError(fmt::format("{}: {}", where_of(file, line), problem));
  throw InputError(fmt::format("{}: {}: {}", where_of(file, line), path, problem));
}

/// Levenshtein distance, for "is 'widht' a typo?" next to a missing key.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

/// A new section for the mapping `node`: keys must be names, each once.
std::shared_ptr<SectionState> make_section(const YAML::Node& node, std::shared_ptr<const std::string> file,
                                           std::string path, int line) {
  if (!node.IsMap()) throw_at(*file, line, path, fmt::format("must be a mapping of keys (got {})", got(node)));
  auto s = std::make_shared<SectionState>();
  s->node = node;
  s->file = std::move(file);
  s->path = std::move(path);
  s->line = line;
  s->is_section = true;
  std::set<std::string> seen;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const int key_line = line_of(it->first, line);
    if (!it->first.IsScalar()) throw_at(*s->file, key_line, s->path, "keys must be names");
    if (!seen.insert(it->first.Scalar()).second)
      throw_at(*s->file, key_line, s->path, fmt::format("key '{}' appears twice", it->first.Scalar()));
  }
  return s;
}

std::string child_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

void finish_state(const SectionState& s) {
  if (s.is_section) {
    for (auto it = s.node.begin(); it != s.node.end(); ++it) {
      const std::string key = it->first.Scalar();
      if (s.read.count(key)) continue;
      const int key_line = line_of(it->first, s.line);
      if (std::find(s.asked.begin(), s.asked.end(), key) != s.asked.end())
        throw_at(*s.file, key_line, s.path, fmt::format("key '{}' is not used here", key));
      std::vector<std::string> allowed = s.asked;
      std::sort(allowed.begin(), allowed.end());
      throw_at(*s.file, key_line, s.path,
               fmt::format("unknown key '{}' (allowed: {})", key, allowed.empty() ? "none" : join(allowed)));
    }
  }
  for (const auto& c : s.children) finish_state(*c);
}

}  // namespace

// ---- loading ---------------------------------------------------------------------------

YAML::Node parse_yaml_text(const std::string& text, const std::string& file, const std::string& what) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    const std::string where = e.mark.line >= 0 ? fmt::format("{}:{}", file, e.mark.line + 1) : file;
    throw InputError(fmt::format("{}: {}: {}", where, what, one_line(e.msg)));
  }
}

YAML::Node load_yaml_file(const std::filesystem::path& file, std::string_view kind) {
  return parse_yaml_text(read_text_file(file, kind), file.string());
}

ConfigSection load_config(const std::filesystem::path& file, std::string_view kind) {
  return ConfigSection(load_yaml_file(file, kind), file.string());
}

// ---- ConfigValue -----------------------------------------------------------------------

ConfigValue::ConfigValue(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), owner_(std::make_shared<SectionState>()), path_(std::move(path)) {
  owner_->file = std::make_shared<const std::string>(std::move(file));
  owner_->path = path_;
  // A document starts on line 1 even when it is empty (yaml-cpp then gives no mark).
  line_ = line_of(node_, path_.empty() ? 1 : 0);
  owner_->line = line_;
}

ConfigValue::ConfigValue(YAML::Node node, std::shared_ptr<SectionState> owner, std::string path, int fallback_line)
    : node_(std::move(node)), owner_(std::move(owner)), path_(std::move(path)) {
  line_ = line_of(node_, fallback_line);
}

const std::string& ConfigValue::file() const { return *owner_->file; }

std::string ConfigValue::where() const { return where_of(file(), line_); }

void ConfigValue::fail(const std::string& problem) const { throw_at(file(), line_, path_, problem); }

void ConfigValue::fail_value(const std::string& problem) const {
  // "'ice.eta' must be ...": the value named by its path.
  if (path_.empty()) throw InputError(fmt::format("{}: value {}", where(), problem));
  throw InputError(fmt::format("{}: '{}' {}", where(), path_, problem));
}

namespace {

// yaml-cpp conversion without its exceptions: false when `n` does not convert.
template <class T>
bool convert(const YAML::Node& n, T& out) {
  if (!n.IsScalar()) return false;
  try {
    out = n.as<T>();
    return true;
  } catch (const YAML::Exception&) {
    return false;
  }
}

}  // namespace

template <>
double ConfigValue::as<double>() const {
  double x = 0;
  if (!convert(node_, x)) fail_value(fmt::format("must be a number (got {})", got(node_)));
  if (!std::isfinite(x)) fail_value(fmt::format("must be a finite number (got {})", got(node_)));
  return x;
}

template <>
int ConfigValue::as<int>() const {
  int x = 0;
  if (!convert(node_, x)) fail_value(fmt::format("must be an integer (got {})", got(node_)));
  return x;
}

template <>
std::int64_t ConfigValue::as<std::int64_t>() const {
  std::int64_t x = 0;
  if (!convert(node_, x)) fail_value(fmt::format("must be an integer (got {})", got(node_)));
  return x;
}

template <>
bool ConfigValue::as<bool>() const {
  bool x = false;
  if (!convert(node_, x)) fail_value(fmt::format("must be true or false (got {})", got(node_)));
  return x;
}

template <>
std::string ConfigValue::as<std::string>() const {
  if (!node_.IsScalar()) fail_value(fmt::format("must be a text value (got {})", got(node_)));
  return node_.Scalar();
}

template <class T>
T ConfigValue::as_in_range(T lo, T hi) const {
  const T x = as<T>();
  if (x < lo || x > hi) fail_value(fmt::format("must be in [{}, {}] (got {})", lo, hi, x));
  return x;
}
template double ConfigValue::as_in_range<double>(double, double) const;
template int ConfigValue::as_in_range<int>(int, int) const;
template std::int64_t ConfigValue::as_in_range<std::int64_t>(std::int64_t, std::int64_t) const;

std::vector<double> ConfigValue::as_numbers(std::size_t n_min, std::size_t n_max) const {
  if (!node_.IsSequence()) fail_value(fmt::format("must be a list of numbers (got {})", got(node_)));
  std::vector<double> v;
  for (const ConfigValue& e : items()) {
    if (e.is_sequence()) {  // a row of a matrix
      for (const ConfigValue& f : e.items()) v.push_back(f.as<double>());
    } else {
      v.push_back(e.as<double>());
    }
  }
  if (v.size() < n_min || v.size() > n_max) {
    if (n_min == n_max) fail_value(fmt::format("must have {} numbers (got {})", n_min, v.size()));
    fail_value(fmt::format("must have {} to {} numbers (got {})", n_min, n_max, v.size()));
  }
  return v;
}

Eigen::Vector3d ConfigValue::as_vec3() const {
  if (!node_.IsSequence() || node_.size() != 3)
    fail_value(fmt::format("must be a list of 3 numbers (got {})", got(node_)));
  const std::vector<ConfigValue> e = items();
  return {e[0].as<double>(), e[1].as<double>(), e[2].as<double>()};
}

std::vector<ConfigValue> ConfigValue::items() const {
  if (!node_.IsSequence()) fail_value(fmt::format("must be a list (got {})", got(node_)));
  std::vector<ConfigValue> out;
  out.reserve(node_.size());
  std::size_t i = 0;
  for (const YAML::Node& e : node_) out.push_back(ConfigValue(e, owner_, fmt::format("{}[{}]", path_, i++), line_));
  return out;
}

ConfigSection ConfigValue::section() const {
  auto s = make_section(node_, owner_->file, path_, line_);
  owner_->children.push_back(s);
  return ConfigSection(std::move(s));
}

void ConfigValue::finish() const { finish_state(*owner_); }

// ---- ConfigSection ---------------------------------------------------------------------

ConfigSection::ConfigSection(YAML::Node node, std::string file, std::string path) {
  const int line = line_of(node, path.empty() ? 1 : 0);
  s_ = make_section(node, std::make_shared<const std::string>(std::move(file)), std::move(path), line);
}

const std::string& ConfigSection::file() const { return *s_->file; }
const std::string& ConfigSection::path() const { return s_->path; }
int ConfigSection::line() const { return s_->line; }
std::string ConfigSection::where() const { return where_of(*s_->file, s_->line); }

void ConfigSection::fail(const std::string& problem) const { throw_at(*s_->file, s_->line, s_->path, problem); }

void ConfigSection::fail_at(const std::string& key, const std::string& problem) const {
  const YAML::Node& n = s_->node;
  const YAML::Node v = n[key];
  throw_at(*s_->file, v ? line_of(v, s_->line) : s_->line, s_->path, problem);
}

bool ConfigSection::has(const std::string& key) const {
  s_->ask(key);
  const YAML::Node& n = s_->node;
  return static_cast<bool>(n[key]);
}

std::vector<std::string> ConfigSection::keys() const {
  std::vector<std::string> out;
  for (auto it = s_->node.begin(); it != s_->node.end(); ++it) out.push_back(it->first.Scalar());
  return out;
}

void ConfigSection::ignore(const std::string& key) const {
  s_->ask(key);
  s_->read.insert(key);
}

std::optional<ConfigValue> ConfigSection::optional_value(const std::string& key) const {
  s_->ask(key);
  const YAML::Node& n = s_->node;  // const: a lookup must not insert the key
  const YAML::Node v = n[key];
  if (!v) return std::nullopt;
  s_->read.insert(key);
  return ConfigValue(v, s_, child_path(s_->path, key), s_->line);
}

ConfigValue ConfigSection::value(const std::string& key) const {
  if (auto v = optional_value(key)) return *v;
  // A key present but not yet asked for, close to the missing one, is likely a typo of it.
  std::string hint;
  std::size_t best = 3;
  for (auto it = s_->node.begin(); it != s_->node.end(); ++it) {
    const std::string k = it->first.Scalar();
    if (s_->read.count(k) || std::find(s_->asked.begin(), s_->asked.end(), k) != s_->asked.end()) continue;
    const std::size_t d = edit_distance(k, key);
    if (d < best && d < key.size()) {
      best = d;
      hint = fmt::format(" (is '{}' a typo?)", k);
    }
  }
  throw_at(*s_->file, s_->line, s_->path, fmt::format("missing key '{}'{}", key, hint));
}

double ConfigSection::require_positive(const std::string& key) const {
  const ConfigValue v = value(key);
  const double x = v.as<double>();
  if (!(x > 0.0)) v.fail_value(fmt::format("must be > 0 (got {})", x));
  return x;
}

std::string ConfigSection::get_choice(const std::string& key, const std::string& fallback,
                                      const std::vector<std::string>& options) const {
  const auto v = optional_value(key);
  if (!v) return fallback;
  if (!v->is_scalar() || std::find(options.begin(), options.end(), v->scalar()) == options.end())
    v->fail_value(fmt::format("must be one of {} (got {})", join(options), got(v->node_)));
  return v->scalar();
}

std::optional<ConfigSection> ConfigSection::optional_section(const std::string& key) const {
  const auto v = optional_value(key);
  if (!v) return std::nullopt;
  return v->section();
}

std::vector<ConfigSection> ConfigSection::sections(const std::string& key) const {
  std::vector<ConfigSection> out;
  for (const ConfigValue& v : value(key).items()) out.push_back(v.section());
  return out;
}

void ConfigSection::finish() const { finish_state(*s_); }

}  // namespace meltlab
