// Every cgal entry of the catalog, checked against CGAL's data archive: extracted through
// dataset_path, then loaded with sim::load_mesh. Entries marked closed_manifold must load
// with the catalogued triangle count, genus and shells; the others must be refused by
// load_mesh (they need repair) and have the catalogued face count. Skipped when
// libcgal-demo is not installed. The cache persists in the build folder between runs.

#include <meltlab/datasets/catalog.h>
#include <meltlab/core/error.h>
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

bool archive_missing() {
  std::error_code ec;
  return !std::filesystem::is_regular_file(cgal_data_archive(), ec);
}

// A loaded closed solid has the entry's triangle count, genus and shells, oriented outward.
void expect_catalogued_solid(const sim::IndexedMesh& mesh, const DatasetEntry& e) {
  EXPECT_EQ(static_cast<std::int64_t>(mesh.F.size()), e.triangles);
  const auto r = test::topology_of(mesh);
  EXPECT_TRUE(r.valid());
  EXPECT_EQ(r.counts.G, e.genus);
  EXPECT_EQ(r.counts.S, e.shells);
  EXPECT_GT(test::signed_volume(mesh), 0.0) << "oriented outward";
}

class CgalArchive : public ::testing::TestWithParam<std::string> {};

TEST_P(CgalArchive, EntryMatchesTheFile) {
  if (archive_missing()) GTEST_SKIP() << "libcgal-demo is not installed (" << cgal_data_archive() << ")";
  const DatasetEntry e = dataset_entry(GetParam());
  const auto file = dataset_path(e.name, MELTLAB_TEST_DATASET_CACHE);
  if (e.closed_manifold) {
    expect_catalogued_solid(sim::load_mesh(file).mesh, e);
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

// Refined entries (the benchmark dragon): generated from their real source into the cache,
// then loaded as a closed solid with exactly the catalogued triangle count and the source's
// genus; the refinement keeps the source's shape (bounding box within 1 % of its diagonal:
// Loop subdivision pulls convex parts in by a fraction of an edge length, the splits move
// nothing).
TEST(CgalArchiveRefined, EntriesMatchTheirTargetAndSource) {
  if (archive_missing()) GTEST_SKIP() << "libcgal-demo is not installed (" << cgal_data_archive() << ")";
  int refined = 0;
  for (const auto& e : dataset_catalog()) {
    if (e.kind != DatasetKind::kRefined) continue;
    SCOPED_TRACE(e.name);
    ++refined;
    const sim::LoadedMesh m = sim::load_mesh(dataset_path(e.name, MELTLAB_TEST_DATASET_CACHE));
    expect_catalogued_solid(m.mesh, e);
    sim::LoadOptions repair;
    repair.repair = true;
    const sim::LoadedMesh src = sim::load_mesh(dataset_path(e.source, MELTLAB_TEST_DATASET_CACHE), repair);
    Eigen::AlignedBox3d box_src, box_ref;
    for (const auto& p : src.mesh.V) box_src.extend(p);
    for (const auto& p : m.mesh.V) box_ref.extend(p);
    const double diag = box_src.diagonal().norm();
    EXPECT_LT((box_src.min() - box_ref.min()).cwiseAbs().maxCoeff(), 0.01 * diag);
    EXPECT_LT((box_src.max() - box_ref.max()).cwiseAbs().maxCoeff(), 0.01 * diag);
  }
  EXPECT_GE(refined, 1);
}

}  // namespace
}  // namespace meltlab::datasets
