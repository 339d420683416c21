// The dataset catalog (catalog.h): the YAML file, generated entries, the cache and the
// extraction of CGAL's meshes.

#include <meltlab/datasets/catalog.h>
#include <meltlab/datasets/molds.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/mesh_io.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <thread>

#include "mesh_checks.h"

namespace meltlab::datasets {
namespace {

namespace fs = std::filesystem;
using sim::IndexedMesh;
using ::testing::HasSubstr;

// The task: each mold within 3 % of its catalogued (monograph) count.
constexpr double kMoldCountTolerance = 0.03;

bool archive_present() {
  std::error_code ec;
  return fs::is_regular_file(cgal_data_archive(), ec);
}

using test::message_of;

using test::write_file;

std::vector<fs::path> leftovers(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().front() == '.') out.push_back(e.path());
  return out;
}

// ---------------------------------------------------------------- the YAML file

TEST(Catalog, ParsesWithUniqueNamesAndEveryKind) {
  const auto entries = dataset_catalog();
  std::set<std::string> names;
  std::map<DatasetKind, int> kinds;
  for (const auto& e : entries) {
    EXPECT_TRUE(names.insert(e.name).second) << "duplicate " << e.name;
    ++kinds[e.kind];
    EXPECT_FALSE(e.description.empty()) << e.name;
    EXPECT_EQ(e.description.find('\n'), std::string::npos) << e.name << ": description is one line";
    EXPECT_GT(e.triangles, 0) << e.name;
    EXPECT_EQ(e.need_repair, !e.closed_manifold) << e.name;
  }
  EXPECT_GE(kinds[DatasetKind::kCgal], 6);
  EXPECT_GE(kinds[DatasetKind::kProcedural], 10);
  EXPECT_EQ(kinds[DatasetKind::kMold], 4);
}

TEST(Catalog, ListsTheRequiredMeshes) {
  std::map<std::string, DatasetEntry> by_name;
  for (auto& e : dataset_catalog()) by_name[e.name] = e;
  for (const char* n : {"bunny00", "ChineseDragon-10kv", "camel", "elephant", "armadillo", "cow"}) {
    ASSERT_TRUE(by_name.count(n)) << n;
    EXPECT_EQ(by_name[n].kind, DatasetKind::kCgal);
  }
  EXPECT_EQ(by_name["bunny00"].triangles, 75408);
  EXPECT_TRUE(by_name["bunny00"].closed_manifold);
  EXPECT_TRUE(by_name["ChineseDragon-10kv"].need_repair);
  EXPECT_TRUE(by_name["cow"].need_repair);
  for (const char* n :
       {"cube_quads", "cube_triangles", "double_cube_quads", "cube_with_face_hole", "cube_with_tunnel",
        "cube_with_tunnel_front_triangulated", "benchmark_a", "benchmark_b", "benchmark_c", "torus", "dumbbell"})
    EXPECT_TRUE(by_name.count(n)) << n;
  for (Mold m : kAllMolds) {
    ASSERT_TRUE(by_name.count(mold_name(m)));
    EXPECT_EQ(by_name[mold_name(m)].triangles, mold_reference_triangles(m));
  }
  EXPECT_EQ(by_name["benchmark_a"].triangles, 192);
  EXPECT_EQ(by_name["benchmark_b"].triangles, 16000);
  EXPECT_EQ(by_name["benchmark_c"].triangles, 32000);
}

TEST(Catalog, BadFilesAreInputErrorsNamingTheFile) {
  const test::TempFolder dir;
  const fs::path f = dir.path() / "catalog.yaml";
  const std::string head = "archive: /nowhere/data.tar.gz\ndatasets:\n";
  const std::string ok = "  - {name: a, kind: procedural, source: cube_triangles, description: x, triangles: 12}\n";
  struct Case {
    std::string text, expect;
  };
  const std::vector<Case> cases = {
      {head + ok + ok, "used twice"},
      {head + "  - {name: a, kind: procedural, source: cube_triangles, description: x, triangles: 12, colour: red}\n",
       "unknown key 'colour'"},
      {head + "  - {name: a, kind: blob, source: x, description: x, triangles: 12}\n", "kind 'blob'"},
      {head + "  - {name: a, kind: procedural, source: cube_triangles, description: x}\n", "missing key 'triangles'"},
      {head + "  - {name: a, kind: procedural, source: teapot, description: x, triangles: 12}\n", "unknown generator"},
      {head + "  - {name: a, kind: mold, source: zebra, description: x, triangles: 12}\n", "unknown mold"},
      {head + "  - {name: a, kind: cgal, source: data/meshes/x.off, description: x, triangles: 12}\n",
       "closed manifold"},
      {head + "  - {name: a, kind: cgal, source: /etc/passwd, description: x, triangles: 1, closed_manifold: true}\n",
       "relative archive member"},
      {head + "  - {name: a, kind: cgal, source: x.off, description: x, triangles: 1, closed_manifold: false}\n",
       "'problem'"},
      {"datasets: []\n", "archive"},
      {head + "  - [1, 2\n", "catalog.yaml:4: YAML syntax error"},
      {"archive: x\ndatasets:\n" + ok + "extra: 1\n",
       "catalog.yaml:4: unknown key 'extra' (allowed: archive, datasets)"},
      {head + ok + "  - {name: b, kind: procedural, source: cube_triangles, description: x, triangles: 0}\n",
       "catalog.yaml:4: datasets[1]: dataset 'b': 'triangles' must be positive"},
  };
  for (const auto& c : cases) {
    write_file(f, c.text);
    const std::string what = message_of([&] { dataset_catalog(f); });
    EXPECT_THAT(what, HasSubstr(f.string())) << c.text;
    EXPECT_THAT(what, HasSubstr(c.expect)) << c.text;
  }
  EXPECT_THAT(message_of([&] { dataset_catalog(dir.path() / "missing.yaml"); }), HasSubstr("not found"));
}

TEST(Catalog, FolderAndArchiveFollowTheEnvironment) {
  const test::TempFolder dir;
  write_file(dir.path() / "catalog.yaml",
             "archive: /custom/data.tar.gz\ndatasets:\n"
             "  - {name: only, kind: procedural, source: cube_triangles, description: x, triangles: 12}\n");
  const test::ScopedEnv folder("MELTLAB_DATASETS_DIR", dir.path().string());
  const test::ScopedEnv archive("MELTLAB_CGAL_DATA_ARCHIVE", std::nullopt);
  EXPECT_EQ(datasets_dir(), dir.path());
  ASSERT_EQ(dataset_catalog().size(), 1u);
  EXPECT_EQ(dataset_catalog().front().name, "only");
  EXPECT_EQ(cgal_data_archive(), fs::path("/custom/data.tar.gz"));
  const test::ScopedEnv archive2("MELTLAB_CGAL_DATA_ARCHIVE", std::string("/other.tar.gz"));
  EXPECT_EQ(cgal_data_archive(), fs::path("/other.tar.gz"));
}

TEST(Catalog, DefaultCacheDirFollowsTheEnvironment) {
  {
    const test::ScopedEnv a("MELTLAB_DATA_DIR", std::string("/data/meltlab"));
    EXPECT_EQ(default_cache_dir(), fs::path("/data/meltlab"));
  }
  const test::ScopedEnv a("MELTLAB_DATA_DIR", std::nullopt);
  {
    const test::ScopedEnv x("XDG_CACHE_HOME", std::string("/xdg"));
    EXPECT_EQ(default_cache_dir(), fs::path("/xdg/meltlab"));
  }
  const test::ScopedEnv x("XDG_CACHE_HOME", std::nullopt);
  {
    const test::ScopedEnv h("HOME", std::string("/home/someone"));
    EXPECT_EQ(default_cache_dir(), fs::path("/home/someone/.cache/meltlab"));
  }
  const test::ScopedEnv h("HOME", std::nullopt);
  EXPECT_THROW(default_cache_dir(), InputError);
}

// ---------------------------------------------------------------- generated entries

TEST(Catalog, EveryGeneratedEntryHasItsCatalogedCountAndTopology) {
  for (const auto& e : dataset_catalog()) {
    if (e.kind == DatasetKind::kCgal || e.kind == DatasetKind::kRefined) continue;  // refined: archive tests
    SCOPED_TRACE(e.name);
    const IndexedMesh m = generated_mesh(e);
    const auto r = test::topology_of(m);
    EXPECT_TRUE(r.valid());
    EXPECT_EQ(r.counts.G, e.genus);
    EXPECT_EQ(r.counts.S, e.shells);
    EXPECT_GT(test::signed_volume(m), 0.0);
    if (e.kind == DatasetKind::kProcedural)
      EXPECT_EQ(static_cast<std::int64_t>(m.F.size()), e.triangles);
    else
      EXPECT_NEAR(static_cast<double>(m.F.size()), static_cast<double>(e.triangles),
                  kMoldCountTolerance * static_cast<double>(e.triangles));
  }
}

TEST(Catalog, GeneratorParametersAreChecked) {
  DatasetEntry e;
  e.name = "probe";
  e.kind = DatasetKind::kProcedural;
  e.source = "uv_sphere";
  e.params = {{"segments", "8"}, {"rings", "4"}};
  EXPECT_EQ(generated_mesh(e).F.size(), 48u);
  e.params["radius"] = "0.5";
  e.params["colour"] = "red";
  EXPECT_THAT(message_of([&] { generated_mesh(e); }), HasSubstr("unknown parameter 'colour'"));
  e.params.erase("colour");
  e.params["rings"] = "four";
  EXPECT_THAT(message_of([&] { generated_mesh(e); }), HasSubstr("'rings' must be an integer"));
  e.params.erase("rings");
  EXPECT_THAT(message_of([&] { generated_mesh(e); }), HasSubstr("needs parameter 'rings'"));
  e.kind = DatasetKind::kCgal;
  EXPECT_THROW(generated_mesh(e), InputError);
}

// ---------------------------------------------------------------- the cache

TEST(DatasetPath, ProceduralEntryRoundTripsThroughTheCache) {
  const test::TempFolder cache;
  const fs::path file = dataset_path("torus", cache.path());
  EXPECT_EQ(file.parent_path(), cache.path());
  EXPECT_THAT(file.filename().string(), ::testing::StartsWith("torus-"));
  const auto when = fs::last_write_time(file);
  EXPECT_EQ(dataset_path("torus", cache.path()), file) << "the second call finds the cached file";
  EXPECT_EQ(fs::last_write_time(file), when) << "and does not rewrite it";

  const IndexedMesh generated = generated_mesh(dataset_entry("torus"));
  const sim::LoadedMesh loaded = sim::load_mesh(file);
  ASSERT_EQ(loaded.mesh.V.size(), generated.V.size());
  ASSERT_EQ(loaded.mesh.F.size(), generated.F.size());
  // sim::save_mesh goes through OpenMesh's writers, which store positions as float: each
  // coordinate comes back rounded to the nearest float (relative error <= 2^-24).
  constexpr double kFloatStorage = 0x1p-24;
  for (std::size_t v = 0; v < generated.V.size(); ++v)
    for (int d = 0; d < 3; ++d)
      EXPECT_LE(std::abs(loaded.mesh.V[v][d] - generated.V[v][d]), kFloatStorage * std::abs(generated.V[v][d])) << v;
  for (std::size_t t = 0; t < generated.F.size(); ++t)
    EXPECT_EQ(sim::rotate_min_first(loaded.mesh.F[t]), sim::rotate_min_first(generated.F[t])) << t;
  EXPECT_TRUE(leftovers(cache.path()).empty());
}

TEST(DatasetPath, DifferentParametersGiveDifferentFiles) {
  const test::TempFolder dir, cache;
  write_file(dir.path() / "catalog.yaml",
             "archive: /nowhere.tar.gz\ndatasets:\n"
             "  - {name: s1, kind: procedural, source: icosphere, params: {subdivisions: 1}, description: x, "
             "triangles: 80}\n"
             "  - {name: s2, kind: procedural, source: icosphere, params: {subdivisions: 2}, description: x, "
             "triangles: 320}\n");
  const test::ScopedEnv folder("MELTLAB_DATASETS_DIR", dir.path().string());
  const fs::path a = dataset_path("s1", cache.path()), b = dataset_path("s2", cache.path());
  EXPECT_NE(a.filename().string().substr(3), b.filename().string().substr(3));
  EXPECT_EQ(sim::load_mesh(a).mesh.F.size(), 80u);
  EXPECT_EQ(sim::load_mesh(b).mesh.F.size(), 320u);
}

TEST(DatasetPath, UnknownNameIsAnInputError) {
  const test::TempFolder cache;
  const std::string what = message_of([&] { dataset_path("teapot", cache.path()); });
  EXPECT_THAT(what, HasSubstr("unknown dataset 'teapot'"));
}

TEST(DatasetPath, MissingArchiveSaysHowToInstallIt) {
  const test::TempFolder cache;
  const test::ScopedEnv archive("MELTLAB_CGAL_DATA_ARCHIVE", (cache.path() / "no-such.tar.gz").string());
  const std::string what = message_of([&] { dataset_path("bunny00", cache.path()); });
  EXPECT_THAT(what, HasSubstr("bunny00"));
  EXPECT_THAT(what, HasSubstr("install libcgal-demo: ./scripts/install-deps"));
  EXPECT_FALSE(fs::exists(cache.path() / "bunny00.off"));
}

TEST(DatasetPath, CorruptArchiveIsAnInputErrorAndLeavesNothingBehind) {
  const test::TempFolder cache;
  const fs::path bad = cache.path() / "bad.tar.gz";
  write_file(bad, "this is not a gzip file");
  const test::ScopedEnv archive("MELTLAB_CGAL_DATA_ARCHIVE", bad.string());
  const std::string what = message_of([&] { dataset_path("camel", cache.path()); });
  EXPECT_THAT(what, HasSubstr("camel: extracting data/meshes/camel.off"));
  EXPECT_THAT(what, HasSubstr("tar exit status"));
  EXPECT_TRUE(leftovers(cache.path()).empty());
}

TEST(DatasetPath, UnwritableCacheIsAnInputError) {
  const test::TempFolder dir;
  write_file(dir.path() / "file", "x");
  EXPECT_THAT(message_of([&] { dataset_path("torus", dir.path() / "file" / "cache"); }),
              HasSubstr("cannot create the dataset cache folder"));
}

TEST(DatasetPath, Bunny00IsExtractedAndLoadsAsAClosedManifold) {
  if (!archive_present()) GTEST_SKIP() << "libcgal-demo is not installed (" << cgal_data_archive() << ")";
  const test::TempFolder cache;
  const fs::path file = dataset_path("bunny00", cache.path());
  EXPECT_EQ(file, cache.path() / "bunny00.off");
  const sim::LoadedMesh m = sim::load_mesh(file);
  EXPECT_EQ(m.mesh.F.size(), 75408u);
  const auto r = test::topology_of(m.mesh);
  EXPECT_TRUE(r.valid());
  EXPECT_EQ(r.counts.G, 0);
  EXPECT_GT(test::signed_volume(m.mesh), 0.0);
  EXPECT_TRUE(leftovers(cache.path()).empty()) << "temporary extraction folders removed";
  const auto when = fs::last_write_time(file);
  EXPECT_EQ(dataset_path("bunny00", cache.path()), file);
  EXPECT_EQ(fs::last_write_time(file), when);
}

// Two processes (and several threads) fetching the same datasets into one empty cache.
TEST(DatasetPath, ConcurrentFetchesAgree) {
  const test::TempFolder cache;
  std::vector<std::string> names = {"benchmark_a", "icosphere_3"};
  if (archive_present()) names.push_back("camel");
  std::vector<pid_t> children;
  for (int k = 0; k < 2; ++k) {
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      int status = 0;
      try {
        for (const auto& n : names) (void)dataset_path(n, cache.path());
      } catch (...) {
        status = 1;
      }
      ::_exit(status);
    }
    children.push_back(pid);
  }
  std::vector<std::thread> threads;
  std::atomic<int> failures{0};
  for (int k = 0; k < 3; ++k)
    threads.emplace_back([&] {
      try {
        for (const auto& n : names) (void)dataset_path(n, cache.path());
      } catch (...) {
        ++failures;
      }
    });
  for (auto& t : threads) t.join();
  for (pid_t pid : children) {
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child process failed";
  }
  EXPECT_EQ(failures.load(), 0);
  for (const auto& n : names) {
    const sim::LoadedMesh m = sim::load_mesh(dataset_path(n, cache.path()));
    EXPECT_EQ(static_cast<std::int64_t>(m.mesh.F.size()), dataset_entry(n).triangles) << n;
  }
  EXPECT_TRUE(leftovers(cache.path()).empty());
}

}  // namespace
}  // namespace meltlab::datasets
