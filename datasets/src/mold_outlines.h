#pragma once
// Hand-placed control points of the four mold outlines (molds.h). Millimetres, x right,
// y up as seen from above, counter-clockwise. A corner point keeps a sharp corner in the
// smoothed outline; the others are passed through smoothly.

#include <meltlab/datasets/molds.h>

#include <vector>

namespace meltlab::datasets::detail {

struct ControlPoint {
  double x_mm = 0, y_mm = 0;
  bool corner = false;
};

/// Control points of the mold's outline (not yet centred).
std::vector<ControlPoint> mold_control_points(Mold mold);

}  // namespace meltlab::datasets::detail
