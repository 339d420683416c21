#pragma once
// Argument checks shared by the generators: each throws meltlab::InputError with a one-line
// message naming the function and the argument.

#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <string_view>

namespace meltlab::datasets::detail {

/// Largest triangle count a generator will produce (indices are 32-bit; far above any
/// mesh the melt model is run on).
inline constexpr std::int64_t kMaxGeneratedTriangles = 200'000'000;

inline void require_positive_length(std::string_view function, std::string_view argument, double value) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw InputError(fmt::format("{}: {} must be a positive finite length, got {}", function, argument, value));
}

inline void require_at_least(std::string_view function, std::string_view argument, std::int64_t value,
                             std::int64_t minimum) {
  if (value < minimum)
    throw InputError(fmt::format("{}: {} must be at least {}, got {}", function, argument, minimum, value));
}

inline void require_triangle_budget(std::string_view function, std::int64_t triangles) {
  if (triangles > kMaxGeneratedTriangles)
    throw InputError(fmt::format("{}: the arguments ask for {} triangles, more than the limit of {}", function,
                                 triangles, kMaxGeneratedTriangles));
}

}  // namespace meltlab::datasets::detail
