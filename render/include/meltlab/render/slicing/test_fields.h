#pragma once
// Seed 003's analytic gradient test fields (spec ../shared/spec/volume-slicing-importance.md §3):
// a sphere (radius 0.35 of the box) and a torus signed-distance field mapped through a smooth step
// of width 2 voxels, f = 1 - smoothstep(-1, 1, sd / voxel) (1 inside, 0 outside), on n³ float32
// node samples in the box [0, 1]³; with their analytic gradient directions (towards increasing f).

#include <meltlab/render/volume/volume.h>

#include <Eigen/Core>

namespace meltlab::render {

enum class TestField { kSphere, kTorus };

/// The signed distance (in voxels) of index point g to the field's surface, and its unit gradient.
double test_field_distance(TestField field, int n, const Eigen::Vector3d& g, Eigen::Vector3d* gradient = nullptr);
/// The field sampled on n³ nodes (n >= 8).
Volume make_test_field(TestField field, int n);

}  // namespace meltlab::render
