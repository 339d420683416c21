#pragma once
// The melting ice body as the renderers see it.

#include <meltlab/core/grid3.h>

namespace meltlab::sim::physics {

/// What the renderer needs of a melting ice body: the solid (ice) volume fraction per cell,
/// in [0, 1]; 0 is air (or drained meltwater). Metres, z up, the ground plane at z = 0.
using IceFraction = Grid3<float>;

}  // namespace meltlab::sim::physics
