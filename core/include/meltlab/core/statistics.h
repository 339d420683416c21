#pragma once
// Small statistics of measurements (timings, residuals): one median for the tree.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace meltlab {

/// The median of `v` (the mean of the two middle values for an even count); 0 for an empty one.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2 == 1) return *mid;
  return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

}  // namespace meltlab
