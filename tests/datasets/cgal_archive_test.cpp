// Every cgal entry of the catalog, checked against CGAL's data archive: extracted through
// dataset_path, then loaded with sim::load_mesh. Entries marked closed_manifold must load
// with the catalogued triangle count, genus and shells; the others must be refused by
// load_mesh (they need repair) and have the catalogued face count. Skipped when
// libcgal-demo is not installed. The cache persists in the build folder between runs.

#include <meltlab/datasets/catalog.h>
#include <meltlab/sim/error.h>
#include <meltlab/sim/mesh_io.h>

#include <gtest/gtest.h>

#include "mesh_checks.h"

#ifndef MELTLAB_TEST_DATASET_CACHE
#error "MELTLAB_TEST_DATASET_CACHE must name the test cache folder"
#endif

namespace meltlab::datasets {
namespace {

std::vector<std::string> cgal_names() {
  std::vector<std::string> out;
  for (const auto& e : dataset_catalog())
    if (e.kind == DatasetKind::kCgal) out.push_back(e.name);
  return out;
}

class CgalArchive : public ::testing::TestWithParam<std::string> {};

TEST_P(CgalArchive, EntryMatchesTheFile) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(cgal_data_archive(), ec))
    GTEST_SKIP() << "libcgal-demo is not installed (" << cgal_data_archive() << ")";
  const DatasetEntry e = dataset_entry(GetParam());
  const auto file = dataset_path(e.name, MELTLAB_TEST_DATASET_CACHE);
  if (e.closed_manifold) {
    const sim::LoadedMesh m = sim::load_mesh(file);
    EXPECT_EQ(static_cast<std::int64_t>(m.mesh.F.size()), e.triangles);
    const auto r = test::topology_of(m.mesh);
    EXPECT_TRUE(r.valid());
    EXPECT_EQ(r.counts.G, e.genus);
    EXPECT_EQ(r.counts.S, e.shells);
    EXPECT_GT(test::signed_volume(m.mesh), 0.0) << "oriented outward";
  } else {
    EXPECT_TRUE(e.need_repair);
    EXPECT_THROW(sim::load_mesh(file), InputError);
    EXPECT_EQ(static_cast<std::int64_t>(sim::read_polygon_mesh(file).faces.size()), e.triangles);
  }
}

INSTANTIATE_TEST_SUITE_P(Catalog, CgalArchive, ::testing::ValuesIn(cgal_names()),
                         [](const ::testing::TestParamInfo<std::string>& p) {
                           std::string s = p.param;
                           for (char& c : s)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return s;
                         });

}  // namespace
}  // namespace meltlab::datasets
