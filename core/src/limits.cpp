#include <meltlab/core/error.h>
#include <meltlab/core/limits.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <mutex>

namespace meltlab {

namespace {

struct LimitField {
  const char* name;
  std::int64_t InputLimits::*member;
};
constexpr LimitField kFields[] = {
    {"mesh_elements", &InputLimits::mesh_elements},
    {"image_pixels", &InputLimits::image_pixels},
    {"volume_samples", &InputLimits::volume_samples},
    {"text_bytes", &InputLimits::text_bytes},
};

std::mutex g_mu;
bool g_initialised = false;
InputLimits g_limits;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

}  // namespace

InputLimits parse_input_limits(std::string_view text, const InputLimits& base, const std::string& what) {
  InputLimits out = base;
  std::string known;
  for (const auto& f : kFields) known += (known.empty() ? "" : ", ") + std::string(f.name);
  while (!text.empty()) {
    const auto comma = text.find(',');
    const std::string_view item = trim(text.substr(0, comma));
    text = comma == std::string_view::npos ? std::string_view() : text.substr(comma + 1);
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string_view::npos)
      throw InputError(fmt::format("{}: '{}' is not name=value (names: {})", what, item, known));
    const std::string name(trim(item.substr(0, eq)));
    const std::string value(trim(item.substr(eq + 1)));
    const LimitField* field = nullptr;
    for (const auto& f : kFields)
      if (name == f.name) field = &f;
    if (!field) throw InputError(fmt::format("{}: unknown limit '{}' (names: {})", what, name, known));
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || !std::isfinite(v) || v < 1 || v > 9.0e18 || v != std::floor(v))
      throw InputError(fmt::format("{}: limit {} must be a positive whole number (got '{}')", what, name, value));
    out.*(field->member) = static_cast<std::int64_t>(v);
  }
  return out;
}

std::string describe_input_limits(const InputLimits& limits) {
  std::string s;
  for (const auto& f : kFields) s += fmt::format("{}{}={}", s.empty() ? "" : ",", f.name, limits.*(f.member));
  return s;
}

const InputLimits& input_limits() {
  std::lock_guard lock(g_mu);
  if (!g_initialised) {
    g_initialised = true;
    if (const char* env = std::getenv("MELTLAB_LIMITS"); env && *env)
      g_limits = parse_input_limits(env, InputLimits{}, "MELTLAB_LIMITS");
  }
  return g_limits;
}

void set_input_limits(const InputLimits& limits) {
  {
    std::lock_guard lock(g_mu);
    g_initialised = true;
    g_limits = limits;
  }
  ::setenv("MELTLAB_LIMITS", describe_input_limits(limits).c_str(), 1);
}

void check_count(const std::string& file, std::string_view what, std::int64_t count, std::int64_t limit,
                 std::string_view limit_name) {
  if (count < 0) throw InputError(fmt::format("{}: {} {} is negative", file, what, count));
  if (count > limit)
    throw InputError(fmt::format("{}: {} {} exceeds the limit of {} (raise it with --limits {}=N)", file, what, count,
                                 limit, limit_name));
}

std::int64_t checked_mul(std::int64_t a, std::int64_t b) {
  if (a < 0 || b < 0) return -1;
  if (a != 0 && b > std::numeric_limits<std::int64_t>::max() / a) return -1;
  return a * b;
}

}  // namespace meltlab
