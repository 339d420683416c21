#pragma once
// Seed 003's view-aligned slices (spec ../shared/spec/volume-slicing-importance.md §2.5): planes
// n · x + d = 0 with n the unit vector from the eye to the volume's centre (vsi.slice.normal,
// vsi.slice.normalise_n: true, so d is a distance), their polygons with the volume's box, the plane
// stack of a Quality class and the samples one pixel ray takes from it.
//
// Frames and units: world frame, scene units. The box is the volume's domain (Volume::domain());
// the source's box has a corner at the origin, ours anywhere (its texture coordinate of x is
// (x - lo) / L).
//
// Plane stack (vsi.slice.qc_map, vsi.slice.d_range, vsi.slice.order): with s = n · x the signed
// depth, [s_min, s_max] = the tight range over the box's corners (the source's conservative ±D
// only adds empty planes; it is kept as an option), Δd = QC · h0 (h0 the smallest voxel spacing),
// and plane k at s_k = s_max - (k + 1/2) Δd, k = 0 .. count - 1, farthest first (back to front).
//
// CPU realisation (vsi.cpu.realisation: per-pixel ray–plane sampling): the GPU rasterises each
// polygon with perspective-correct texture coordinates; a pixel covered by polygon k samples the
// point where its ray meets plane k. The renderer intersects each pixel's ray with the planes
// instead (ray_slice_samples): the same points, with no rasteriser (slicing_geometry_test shows it).

#include <meltlab/render/volume/volume.h>

#include <Eigen/Core>

#include <vector>

namespace meltlab::render {

/// The polygon of the plane n · x + d = 0 with the box: 3-6 vertices on box edges, corners
/// deduplicated, convex, counter-clockwise seen from the tip of n (sorted by atan2 in a plane basis,
/// equivalent to the source's signed arccos). Empty when the plane misses the box or touches it
/// in fewer than 3 distinct points. n need not be unit.
std::vector<Eigen::Vector3d> slice_polygon(const Box3& box, const Eigen::Vector3d& n, double d);

/// Area of a planar polygon (vertices in order) with unit normal n (positive when counter-clockwise).
double polygon_area(const std::vector<Eigen::Vector3d>& polygon, const Eigen::Vector3d& n);

/// vsi.slice.d_range.
enum class SliceRange {
  kTight,         ///< s ∈ [min, max] of n · corner (the harness's default)
  kConservative,  ///< the source's |d| <= D = |n_x| L_x + |n_y| L_y + |n_z| L_z about the box's lower corner
};

/// The planes of one frame.
struct SliceStack {
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ();  ///< unit, from the eye towards the box centre
  double s_max = 0;                              ///< the farthest depth of the range
  double spacing = 1;                            ///< Δd (scene units)
  int count = 0;                                 ///< planes k = 0 .. count - 1
  /// Depth s_k = n · x of plane k (the plane's d is -s_k).
  double depth(int k) const { return s_max - (k + 0.5) * spacing; }
};

/// The stack for an eye and a spacing Δd > 0 (InputError for an eye at the box centre or a
/// non-positive spacing; more than 1e6 planes is refused too).
SliceStack slice_stack(const Box3& box, const Eigen::Vector3d& eye, double spacing,
                       SliceRange range = SliceRange::kTight);

/// Δd of a Quality class: QC · h0 with h0 the smallest spacing of the volume (vsi.slice.qc_map).
double slice_spacing(double quality_class, const Eigen::Vector3d& voxel_spacing);

/// The planes one ray meets inside the box, back to front: the ray o + t v (v unit, o the eye)
/// meets plane k at t_k = (s_k - n · o) / (n · v). Returns the first and last plane index
/// (k_first <= k_last, farthest first) or k_first > k_last when none; requires n · v > 0 (rays of
/// a camera looking at the box with a field of view below 180°).
struct RaySlices {
  int k_first = 0, k_last = -1;
  double t_offset = 0;  ///< t_k = (s_k - n · o) / cos ψ
  double cos_psi = 1;   ///< n · v
  bool empty() const { return k_first > k_last; }
  double t(const SliceStack& st, int k) const { return (st.depth(k) - t_offset) / cos_psi; }
};
RaySlices ray_slices(const SliceStack& stack, const Box3& box, const Eigen::Vector3d& o, const Eigen::Vector3d& v);

}  // namespace meltlab::render
