// repair_closed_solid: each kind of defect is fixed, recorded in `actions`, and the result
// is a valid closed solid (by the project's own check) enclosing the expected volume.

#include <meltlab/sim/cgal/repair.h>
#include <meltlab/sim/cgal/self_intersection.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/topology.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "cgal_test_meshes.h"

namespace meltlab::sim {
namespace {

using test::V3;
using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::StartsWith;

// Volumes are sums of products of small integers and halves: exact up to rounding.
constexpr double kVolumeTolerance = 1e-12;

enum class Contact { kNone, kTouching };

// Checks what every repair must deliver and returns the enclosed volume. Parts of the
// result may only touch where the input had them share a vertex (`contact`).
double checked_volume(const RepairResult& r, Contact contact = Contact::kNone) {
  const TriMesh<double> m = TriMesh<double>::from_indexed(r.mesh);
  const TopologyReport topo = check_topology(m);
  EXPECT_TRUE(topo.valid()) << (topo.problems.empty() ? std::string("?") : topo.problems.front().describe());
  EXPECT_EQ(topo.counts.chi, 0);
  EXPECT_EQ(self_intersections(m).intersects, contact == Contact::kTouching);
  return test::signed_volume(r.mesh);
}

TEST(RepairClosedSolid, ValidCubeIsOnlyTriangulated) {
  const RepairResult r = repair_closed_solid(test::quad_cube(), "cube.obj");
  EXPECT_THAT(r.actions, IsEmpty());
  EXPECT_EQ(r.mesh.V.size(), 8u);
  EXPECT_EQ(r.mesh.F.size(), 12u);
  EXPECT_NEAR(checked_volume(r), 1.0, kVolumeTolerance);
}

TEST(RepairClosedSolid, CubeWithAMissingFaceIsClosed) {
  PolygonMesh open = test::quad_cube();
  open.faces.erase(open.faces.begin() + 1);  // the top
  const RepairResult r = repair_closed_solid(open, "open.obj");
  ASSERT_EQ(r.actions.size(), 1u);
  EXPECT_THAT(r.actions[0], StartsWith("filled 1 hole with "));
  // The patch stays in the plane of the missing face: refinement, no fairing.
  EXPECT_NEAR(checked_volume(r), 1.0, kVolumeTolerance);
  for (const auto& p : r.mesh.V) EXPECT_LE(p.z(), 1.0);
}

TEST(RepairClosedSolid, FlippedFaceIsTurnedBack) {
  // Face 0 flipped makes orient_polygon_soup start from the wrong side (it keeps the
  // first polygon of a component); face 5 flipped does not. Either way one polygon turns.
  for (std::size_t f : {0u, 5u}) {
    const RepairResult r = repair_closed_solid(test::with_face_flipped(test::quad_cube(), f), "flipped.obj");
    EXPECT_THAT(r.actions, Contains("reversed orientation of 1 of 6 polygons")) << "face " << f;
    EXPECT_NEAR(checked_volume(r), 1.0, kVolumeTolerance);
  }
}

TEST(RepairClosedSolid, InsideOutCubeIsReversed) {
  PolygonMesh inside_out = test::quad_cube();
  for (std::size_t f = 0; f < inside_out.faces.size(); ++f) inside_out = test::with_face_flipped(inside_out, f);
  const RepairResult r = repair_closed_solid(inside_out, "inside_out.obj");
  EXPECT_THAT(r.actions, Contains("reversed orientation of all 6 polygons (the input was inside-out)"));
  EXPECT_NEAR(checked_volume(r), 1.0, kVolumeTolerance);
}

TEST(RepairClosedSolid, CubesSharingACornerAreSplitApart) {
  // [0,1]³ and [1,2]³ through one vertex slot at (1,1,1): a non-manifold vertex.
  PolygonMesh two = test::polygon_union(test::quad_cube(), test::quad_cube(V3(1, 1, 1)));
  const Index shared = 7, duplicate = 8 + 0;
  for (auto& f : two.faces)
    for (auto& v : f.outer)
      if (v == duplicate) v = shared;
  two.V.erase(two.V.begin() + duplicate);  // unused now; later indices shift by one
  for (auto& f : two.faces)
    for (auto& v : f.outer)
      if (v > duplicate) --v;
  ASSERT_FALSE(check_topology(two).valid());
  const RepairResult r = repair_closed_solid(two, "corner.obj");
  EXPECT_THAT(r.actions, Contains("split 1 non-manifold vertex"));
  EXPECT_EQ(r.mesh.V.size(), 16u);
  EXPECT_EQ(r.mesh.F.size(), 24u);
  // The two corners are now separate vertices at the same point: the cubes touch there.
  EXPECT_NEAR(checked_volume(r, Contact::kTouching), 2.0, kVolumeTolerance);
}

TEST(RepairClosedSolid, SoupDefectsAreCounted) {
  // An STL-like soup: every face has its own corners; plus one face twice.
  const PolygonMesh cube = test::quad_cube();
  PolygonMesh soup;
  for (const auto& f : cube.faces) {
    PolygonFace g;
    for (Index v : f.outer) {
      g.outer.push_back(static_cast<Index>(soup.V.size()));
      soup.V.push_back(cube.V[static_cast<std::size_t>(v)]);
    }
    soup.faces.push_back(g);
  }
  soup.faces.push_back(soup.faces[2]);
  const RepairResult r = repair_closed_solid(soup, "soup.stl");
  EXPECT_THAT(r.actions, Contains("merged 16 duplicate points"));
  EXPECT_THAT(r.actions, Contains("removed 1 duplicate polygon"));
  EXPECT_EQ(r.mesh.V.size(), 8u);
  EXPECT_NEAR(checked_volume(r), 1.0, kVolumeTolerance);
}

TEST(RepairClosedSolid, SphereWithACapCutOffIsRefilledWithNewVertices) {
  IndexedMesh sphere = test::icosphere(3);
  PolygonMesh open;
  open.V = sphere.V;
  for (const auto& t : sphere.F) {
    const double z = (sphere.V[static_cast<std::size_t>(t[0])] + sphere.V[static_cast<std::size_t>(t[1])] +
                      sphere.V[static_cast<std::size_t>(t[2])])
                         .z() /
                     3.0;
    if (z < 0.6) open.faces.push_back({{t[0], t[1], t[2]}, {}});
  }
  const RepairResult r = repair_closed_solid(open, "cap.off");
  EXPECT_THAT(r.actions, Contains(StartsWith("filled 1 hole with ")));
  EXPECT_THAT(r.actions, Contains(HasSubstr("new vertices")));
  EXPECT_GT(checked_volume(r), 0.0);
}

TEST(RepairClosedSolid, SingleTriangleCannotBeRepaired) {
  PolygonMesh tri;
  tri.V = {V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0)};
  tri.faces = {{{0, 1, 2}, {}}};
  try {
    repair_closed_solid(tri, "tri.off");
    FAIL() << "a single triangle bounds no solid";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith("tri.off: cannot repair: "));
  }
}

TEST(RepairClosedSolid, FaceWithAHoleIsRefused) {
  PolygonMesh holed = test::quad_cube();
  holed.V.push_back(V3(0.25, 0.25, 1));
  holed.V.push_back(V3(0.25, 0.75, 1));
  holed.V.push_back(V3(0.75, 0.75, 1));
  holed.faces[1].holes.push_back({8, 9, 10});
  try {
    repair_closed_solid(holed, "holed.obj");
    FAIL() << "faces with holes are not supported";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), StartsWith("holed.obj: cannot repair: face 1 has 1 hole"));
  }
}

TEST(RepairClosedSolid, BadIndicesAndCoordinatesAreRefused) {
  PolygonMesh bad_index = test::quad_cube();
  bad_index.faces[3].outer[2] = 42;
  EXPECT_THROW(repair_closed_solid(bad_index, "bad.obj"), InputError);
  PolygonMesh bad_point = test::quad_cube();
  bad_point.V[2].y() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(repair_closed_solid(bad_point, "bad.obj"), InputError);
  EXPECT_THROW(repair_closed_solid(PolygonMesh{}, "empty.obj"), InputError);
}

}  // namespace
}  // namespace meltlab::sim
