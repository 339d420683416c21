#include <meltlab/core/error.h>
#include <meltlab/sim/mesh_io.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "test_files.h"
#include "hand_meshes.h"

namespace meltlab::sim {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

class MeshIo : public ::testing::Test {
 protected:
  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }
  std::string load_error(const fs::path& p, LoadOptions opt = {}) {
    try {
      load_mesh(p, opt);
    } catch (const InputError& e) {
      return e.what();
    }
    return "no error";
  }
  test::TempFolder folder_;
  const fs::path dir_ = folder_.path();
};

// OBJ and STL store float32 coordinates.
constexpr double kFloatStorage = 1e-6;

TEST_F(MeshIo, RoundTripEveryFormat) {
  const IndexedMesh oct = test::octahedron(0.25);
  for (const std::string ext : {"off", "ply", "obj", "stl"}) {
    const fs::path p = dir_ / ("oct." + ext);
    save_mesh(oct, p);
    const LoadedMesh in = load_mesh(p);
    EXPECT_EQ(in.mesh.V.size(), 6u) << ext;
    EXPECT_EQ(in.mesh.F.size(), 8u) << ext;
    EXPECT_EQ(in.report.file_counts.chi, 0) << ext;
    double vol = 0;
    for (const auto& t : in.mesh.F)
      vol += in.mesh.V[static_cast<std::size_t>(t[0])].dot(
                 in.mesh.V[static_cast<std::size_t>(t[1])].cross(in.mesh.V[static_cast<std::size_t>(t[2])])) /
             6.0;
    EXPECT_NEAR(vol, 4.0 / 3.0 * 0.25 * 0.25 * 0.25, kFloatStorage) << ext << ": orientation or positions changed";
  }
}

TEST_F(MeshIo, StlSoupIsWelded) {
  const fs::path p = dir_ / "cube.stl";
  save_mesh(test::cube12(), p);
  const LoadedMesh in = load_mesh(p);
  EXPECT_EQ(in.mesh.V.size(), 8u);
  EXPECT_EQ(in.mesh.F.size(), 12u);
}

TEST_F(MeshIo, NoTemporaryFilesLeftAfterSave) {
  save_mesh(test::cube12(), dir_ / "a.ply");
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir_)) {
    ++n;
    EXPECT_EQ(e.path().filename(), "a.ply");
  }
  EXPECT_EQ(n, 1u);
}

TEST_F(MeshIo, QuadCubeKeepsPolygonCountsAndTriangulates) {
  const fs::path p = write("quads.off",
                           "OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                           "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
  const LoadedMesh in = load_mesh(p);
  EXPECT_EQ(in.report.file_counts.E, 12);
  EXPECT_EQ(in.report.file_counts.F, 6);
  EXPECT_EQ(in.report.file_counts.chi, 0);
  EXPECT_EQ(in.mesh.F.size(), 12u);
}

TEST_F(MeshIo, UnreferencedVertexIsDropped) {
  const fs::path p =
      write("extra.off", "OFF\n5 4 0\n-1 0 1\n0 0 -1\n1 0 1\n0 1 0\n7 7 7\n3 3 1 0\n3 3 2 1\n3 3 0 2\n3 1 2 0\n");
  const LoadedMesh in = load_mesh(p);
  EXPECT_EQ(in.report.unreferenced_vertices, 1u);
  EXPECT_EQ(in.mesh.V.size(), 4u);
}

TEST_F(MeshIo, WeldToleranceMergesNearDuplicates) {
  // A tetrahedron whose last face uses copies of its vertices shifted by 1e-7.
  const std::string text =
      "OFF\n7 4 0\n-1 0 1\n0 0 -1\n1 0 1\n0 1 0\n0.0000001 0 -1\n1 0.0000001 1\n-1 0 1.0000001\n"
      "3 3 1 0\n3 3 2 1\n3 3 0 2\n3 4 5 6\n";
  const fs::path p = write("near.off", text);
  EXPECT_THAT(load_error(p), HasSubstr("boundary edge"));
  LoadOptions opt;
  opt.weld_tolerance = 1e-6;
  const LoadedMesh in = load_mesh(p, opt);
  EXPECT_EQ(in.report.welded_vertices, 3u);
  EXPECT_EQ(in.mesh.V.size(), 4u);
}

TEST_F(MeshIo, MissingEmptyUnknownFormat) {
  EXPECT_THAT(load_error(dir_ / "nope.off"), AllOf(HasSubstr("nope.off"), HasSubstr("no such file")));
  EXPECT_THAT(load_error(write("empty.off", "")), AllOf(HasSubstr("empty.off"), HasSubstr("empty")));
  EXPECT_THAT(load_error(write("mesh.xyz", "1 2 3")), HasSubstr("unknown mesh format"));
  EXPECT_THAT(load_error(dir_), HasSubstr("folder"));
}

TEST_F(MeshIo, GarbageAndTruncatedFilesAreRefused) {
  EXPECT_THAT(load_error(write("garbage.off", "this is not a mesh\n")), HasSubstr("garbage.off"));
  EXPECT_THAT(load_error(write("garbage.ply", "ply\nformat nonsense\n")), HasSubstr("garbage.ply"));
  EXPECT_THAT(load_error(write("trunc.off", "OFF\n4 4 0\n-1 0 1\n0 0 -1\n1 0 1\n0 1 0\n3 3 1 0\n3 3 2 1\n")),
              HasSubstr("trunc.off"));
  // A binary PLY cut in the middle of its data.
  save_mesh(test::octahedron(), dir_ / "full.ply");
  std::ifstream full(dir_ / "full.ply", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(full)), {});
  const fs::path cut = write("cut.ply", bytes.substr(0, bytes.size() - 20));
  EXPECT_THAT(load_error(cut), HasSubstr("cut.ply"));
}

TEST_F(MeshIo, NonFiniteCoordinateIsNamed) {
  const std::string msg =
      load_error(write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"));
  EXPECT_THAT(msg, HasSubstr("nan.obj:line 3"));
  EXPECT_THAT(msg, HasSubstr("not a finite number"));
  const std::string off =
      load_error(write("nan.off", "OFF\n4 4 0\n-1 0 1\n0 0 -1\n1 nan 1\n0 1 0\n3 3 1 0\n3 3 2 1\n3 3 0 2\n3 1 2 0\n"));
  EXPECT_THAT(off, HasSubstr("nan.off:line 5: vertex v2 coordinate 'nan' is not a finite number"));
  const std::string inf =
      load_error(write("inf.off", "OFF\n4 4 0\n-1 0 1\n0 0 -1\n1 inf 1\n0 1 0\n3 3 1 0\n3 3 2 1\n3 3 0 2\n3 1 2 0\n"));
  EXPECT_THAT(inf, HasSubstr("inf.off:line 5: vertex v2"));
}

TEST_F(MeshIo, OpenAndNonManifoldInputIsRefusedWithTheEdge) {
  EXPECT_THAT(load_error(write("open.off", "OFF\n4 3 0\n-1 0 1\n0 0 -1\n1 0 1\n0 1 0\n3 3 1 0\n3 3 2 1\n3 3 0 2\n")),
              AllOf(HasSubstr("open.off"), HasSubstr("open mesh"), HasSubstr("boundary edge"), HasSubstr("--repair")));
  // Octahedron with a tetrahedral fin on edge (0, 2).
  const std::string fin =
      "OFF\n8 12 0\n1 0 0\n-1 0 0\n0 1 0\n0 -1 0\n0 0 1\n0 0 -1\n0.5 0.5 -2\n0.6 0.6 -3\n"
      "3 0 2 4\n3 2 1 4\n3 1 3 4\n3 3 0 4\n3 2 0 5\n3 1 2 5\n3 3 1 5\n3 0 3 5\n"
      "3 0 6 2\n3 2 6 7\n3 0 7 6\n3 0 2 7\n";
  EXPECT_THAT(load_error(write("fin.off", fin)), AllOf(HasSubstr("fin.off"), HasSubstr("non-manifold edge (v0, v2)")));
}

}  // namespace
}  // namespace meltlab::sim
