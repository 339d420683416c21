#pragma once
// Procedural closed solids: the example polyhedra of the monograph's Tab. 2.3, the timing
// objects A/B/C of Tab. 5.1, spheres, a torus and a dumbbell that pinches apart when it
// shrinks.
//
// Every mesh returned here is closed, manifold and oriented outward: each face loop is
// counter-clockwise seen from outside, so (b - a) x (c - a) points out of the solid and the
// signed volume is positive. Hole loops of PolygonFace::holes run clockwise seen from
// outside. Vertices are unique (no duplicates to weld) and every vertex is used.
//
// Units: lengths are metres (any unit works; the defaults are sized like the monograph's
// ~10 cm ice objects). Frame: object frame, z up; shapes are centred on the origin unless
// stated. Bad arguments (a count below its minimum, a non-positive or non-finite length)
// throw meltlab::InputError naming the function and the argument.

#include <meltlab/sim/mesh.h>
#include <meltlab/sim/polygon_mesh.h>

namespace meltlab::datasets {

using sim::IndexedMesh;
using sim::PolygonMesh;

// === Tab. 2.3 polyhedra (polygon form; the table's V E F H S G in brackets) ===

/// Axis-aligned cube of side `edge` centred on the origin, 6 quads [V8 E12 F6 H0 S1 G0].
PolygonMesh cube_quads(double edge = 1.0);

/// The same cube with every quad split along one diagonal: 12 triangles [V8 E18 F12].
IndexedMesh cube_triangles(double edge = 1.0);

/// Two disjoint quad cubes of side `edge`: one centred on the origin, the other on
/// (2 edge, 0, 0) [V16 E24 F12 H0 S2 G0].
PolygonMesh double_cube_quads(double edge = 1.0);

/// Cube of side `edge` with a blind square pocket (side edge/2, depth edge/2) sunk into its
/// top (+z) face. The top face is one polygon with one hole loop [V16 E24 F11 H1 S1 G0].
PolygonMesh cube_with_face_hole(double edge = 1.0);

/// Cube of side `edge` with a square tunnel (side edge/2) along y, from the front (-y) face
/// to the back (+y) face; both are polygons with a hole [V16 E24 F10 H2 S1 G1].
PolygonMesh cube_with_tunnel(double edge = 1.0);

/// `cube_with_tunnel` with the front (-y) annulus split into 8 triangles, so only the back
/// face keeps its hole [V16 E32 F17 H1 S1 G1].
PolygonMesh cube_with_tunnel_front_triangulated(double edge = 1.0);

// === Triangle meshes ===

/// Cube of side `edge` centred on the origin whose faces are n x n grids of quads, each
/// split into two triangles: 6 n² + 2 vertices, 12 n² triangles. Requires n >= 1.
/// n = 4 is the monograph's timing object A (98 vertices, 192 triangles).
IndexedMesh subdivided_cube(int n, double edge = 1.0);

/// Latitude-longitude sphere centred on the origin with poles on the z axis: `rings`
/// latitude bands (rings - 1 vertex rings of `segments` vertices, plus the two poles).
/// Vertices segments (rings - 1) + 2, triangles 2 segments (rings - 1). The vertices lie on
/// the sphere, so the enclosed volume is slightly below 4/3 pi radius³.
/// Requires segments >= 3, rings >= 2.
IndexedMesh uv_sphere(int segments, int rings, double radius = 1.0);

/// Geodesic sphere: an icosahedron whose triangles are split into 4 `subdivisions` times,
/// vertices pushed onto the sphere: 20·4^k triangles, 10·4^k + 2 vertices. 0 <= k <= 9.
IndexedMesh icosphere(int subdivisions, double radius = 1.0);

/// Geodesic sphere: every face of the icosahedron split into frequency² triangles on a
/// regular barycentric grid, projected onto the sphere: 20·f² triangles, 10·f² + 2 vertices,
/// nearly uniform (edge lengths within about ±20%), no poles. f = 40 gives 32000 triangles.
IndexedMesh geodesic_sphere(int frequency, double radius = 1.0);

/// A uv_sphere with exactly `triangles` triangles: segments·(rings - 1) = triangles / 2,
/// choosing among the factorisations the one with segments closest to 2 (rings - 1), so the
/// equatorial quads are closest to square. `triangles` must be even (3F = 2E for a closed
/// triangle mesh) and >= 6.
IndexedMesh sphere_with_triangles(int triangles, double radius = 1.0);

/// Closed cylinder around the z axis, centred on the origin (z from -height/2 to height/2):
/// two rings of `segments` vertices on the circle of `radius`, a centre vertex on each cap,
/// 2 segments + 2 vertices, 4 segments triangles. Its volume is exactly that of the inscribed
/// prism, segments/2 · radius² · sin(2π/segments) · height. Requires segments >= 3.
IndexedMesh cylinder(double radius, double height, int segments);

/// Ring torus around the z axis, centred on the origin: tube centre-line radius
/// `major_radius`, tube radius `minor_radius` (0 < minor < major), `major_segments`
/// vertices around the axis and `minor_segments` around the tube (each >= 3).
/// Genus 1; major·minor vertices, 2·major·minor triangles.
IndexedMesh torus(double major_radius, double minor_radius, int major_segments, int minor_segments);

/// Two balls joined by a thin cylindrical neck, as one surface of revolution about the x
/// axis (a single closed manifold: no internal faces, no duplicate vertices). The neck
/// meets each ball through a concave circular fillet, so the profile is C1. The profile is
/// sampled by arc length at `edge_length_m` and each vertex ring gets round(2 pi rho / edge)
/// vertices (at least 3), so triangles are of roughly uniform size everywhere, the neck
/// included. A shrinking model pinches the neck first and splits the solid into 2 shells.
struct DumbbellOptions {
  double ball_radius_m = 0.02;     ///< radius of each ball
  double ball_gap_m = 0.024;       ///< distance between the two ball surfaces along the axis
  double neck_radius_m = 0.004;    ///< radius of the cylindrical neck, < ball_radius_m
  double fillet_radius_m = 0.004;  ///< radius of the concave fillets joining neck and balls
  double edge_length_m = 0.0025;   ///< target triangle edge length
};
/// Default options: total length 2·0.02 + 0.024 + 2·0.02 = 0.104 m, a straight neck of
/// about 19 mm resolved by 7 vertex rings of 10 vertices, 3344 triangles whose edges are
/// 2.4–4.4 mm long.
/// Throws InputError if the fillets do not fit between the balls or the neck is not
/// thinner than the balls.
IndexedMesh dumbbell(const DumbbellOptions& options = {});

/// The timing objects of the monograph's Tab. 5.1 (§6.5), as stand-ins of equal size:
///   'A': subdivided_cube(4, 0.1 m)          — 192 triangles, 98 vertices
///   'B': uv_sphere(100, 81, radius 0.05 m)  — 16000 triangles
///   'C': uv_sphere(160, 101, radius 0.05 m) — 32000 triangles
/// Lower case is accepted. Any other letter throws InputError.
IndexedMesh benchmark_object(char which);

}  // namespace meltlab::datasets
