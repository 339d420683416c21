#pragma once
// Stand-ins for the four ice molds of the monograph's verification (§9.4, Fig. 8.5): flat
// ice blocks whose outline, seen from above, is a giraffe, an airplane, a ship or a
// warship. The photographed molds are not public; these outlines are authored by hand so
// that they are recognisable and have the monograph's mesh sizes, not copied from it.
//
// Outline: a simple polygon in the xy plane, counter-clockwise seen from above (+z),
// millimetres, its bounding box centred on the origin. It is a centripetal Catmull-Rom
// spline through hand-placed control points (corner points keep a sharp corner), sampled
// at <= 0.5 mm, so curves are smooth while legs, necks and gun barrels stay thin.
//   giraffe  — side view, head to +x: body, four legs, long neck, head with two
//              ossicones and an ear, tail with a tuft;                153 x 184 mm
//   airplane — top view, nose to +y: fuselage, swept wings with engine nacelles,
//              tailplane, tail cone (the fin seen end-on);            177 x 179 mm
//   ship     — side view, bow to +x: hull with raked bow and rounded stern, two-tier
//              deck house, slanted funnel, foremast;                  173 x 92 mm
//   warship  — side view, bow to +x: long low hull with pointed bow, four gun turrets
//              with barrels, stepped bridge tower, funnel, mast;      184 x 93 mm
//
// Block: the outline extruded from z = 0 (bottom face) to z = thickness (top face), in
// metres. The thickness makes the block hold `ice_mass_kg` of ice (monograph §9.2: about
// 250 g): thickness = mass / (density · outline area). With the defaults (250 g, 917 kg/m³,
// 272.6 cm³) the thicknesses are
//   giraffe 30.5 mm, airplane 25.9 mm, ship 29.4 mm, warship 31.1 mm
// (outline areas 89.5, 105.4, 92.7 and 87.6 cm²).
// Top and bottom faces share one 2-D mesh: CGAL's constrained Delaunay triangulation of
// the resampled outline refined by CGAL::Delaunay_mesher_2 (minimum angle about 20.6°,
// edge-length bound h), so triangles are well shaped and of nearly uniform size; the side
// wall is `rows` rows of quads (rows = round(thickness / boundary spacing)) through the
// same outline vertices, each split into two triangles. h is found by bisection so the
// triangle count is close to the target (by default the monograph's count for the mold:
// giraffe 10823, airplane 10683, ship 10874, warship 10799).
//
// The mesh is closed, manifold, genus 0 and oriented outward (triangles counter-clockwise
// seen from outside).

#include <meltlab/sim/mesh.h>

#include <Eigen/Core>

#include <array>
#include <string>
#include <string_view>
#include <vector>

namespace meltlab::datasets {

enum class Mold { kGiraffe, kAirplane, kShip, kWarship };

inline constexpr std::array<Mold, 4> kAllMolds = {Mold::kGiraffe, Mold::kAirplane, Mold::kShip, Mold::kWarship};

/// "giraffe", "airplane", "ship", "warship".
std::string mold_name(Mold mold);

/// Inverse of mold_name (exact, lower case); throws InputError listing the valid names.
Mold mold_from_name(std::string_view name);

/// Triangle count of the mold's mesh in the monograph (§9.4): 10823, 10683, 10874, 10799.
int mold_reference_triangles(Mold mold);

/// The smoothed outline: simple polygon, CCW seen from +z, millimetres, bounding box
/// centred on the origin, consecutive points <= 0.5 mm apart (first point not repeated).
/// This is the same frame as mold_mesh (which is in metres): p_mesh = p_outline / 1000.
std::vector<Eigen::Vector2d> mold_outline_mm(Mold mold);

/// Signed area of a closed polygon (shoelace), positive when counter-clockwise; units²
/// of the input.
double polygon_area(const std::vector<Eigen::Vector2d>& polygon);

struct MoldOptions {
  int target_triangles = 0;          ///< 0: the monograph's count (mold_reference_triangles)
  double max_count_error = 0.03;     ///< accepted |count - target| / target, else InputError
  double ice_mass_kg = 0.25;         ///< sets the thickness (monograph §9.2: about 250 g)
  double ice_density_kg_m3 = 917.0;  ///< density of ice at about 0 °C
  double thickness_m = 0.0;          ///< > 0: use this thickness instead of the mass
};

/// A mold block and the parameters it was built with (to log beside a run).
struct MoldBlock {
  sim::IndexedMesh mesh;       ///< metres, z up, bottom face at z = 0, CCW from outside
  double thickness_m = 0;      ///< block height
  double outline_area_m2 = 0;  ///< area of the top face
  double size_bound_m = 0;     ///< CGAL edge-length bound h of the top/bottom mesh
  int boundary_vertices = 0;   ///< outline vertices (per face)
  int wall_rows = 0;           ///< rows of quads on the side wall
  int target_triangles = 0;    ///< the count aimed at
};

/// Builds the block. Throws InputError for non-positive mass, density or thickness, a
/// target below 200 triangles, or if no size bound gets within max_count_error.
MoldBlock mold_block(Mold mold, const MoldOptions& options = {});

/// mold_block(mold, options).mesh.
sim::IndexedMesh mold_mesh(Mold mold, const MoldOptions& options = {});

}  // namespace meltlab::datasets
