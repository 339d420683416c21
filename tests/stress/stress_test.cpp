// Stress: melt every dataset mesh until it disappears, checking that no coordinate becomes
// NaN/inf and that the topology stays valid (every 100 cycles), and sampling CGAL's
// self-intersection test; then M_N-only against the combined displacement (Figs. 3.1 vs
// 3.5): the cycle at which each first makes the surface intersect itself.
//
// Two sizes: the reduced set (ctest label `stress`, part of the default suite) and the full
// set (label `soak`: every closed catalog mesh, up to 60000 cycles). The environment variable
// MELTLAB_STRESS_FULL=1 selects the full set. Results are written as CSV into
// $MELTLAB_RESULTS_DIR (default: ./results) for the report.

#include <meltlab/datasets/catalog.h>
#include <meltlab/sim/cgal/self_intersection.h>
#include <meltlab/sim/melt.h>
#include <meltlab/sim/mesh_io.h>
#include <meltlab/sim/mesh_order.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace meltlab {
namespace {

namespace fs = std::filesystem;

bool full_run() {
  const char* v = std::getenv("MELTLAB_STRESS_FULL");
  return v && std::string(v) == "1";
}

fs::path results_dir() {
  const char* v = std::getenv("MELTLAB_RESULTS_DIR");
  fs::path dir = v ? fs::path(v) : fs::path("results");
  fs::create_directories(dir);
  return dir;
}

sim::IndexedMesh load_dataset(const datasets::DatasetEntry& e) {
  sim::LoadOptions opt;
  opt.repair = e.need_repair;
  return sim::reorder_for_locality(sim::load_mesh(datasets::dataset_path(e.name), opt).mesh).mesh;
}

sim::MeltParams default_params(const sim::IndexedMesh& m) { return sim::relative_melt_params(m); }

std::vector<datasets::DatasetEntry> stress_meshes() {
  std::vector<datasets::DatasetEntry> out;
  const auto catalog = datasets::dataset_catalog();
  if (full_run()) {
    for (const auto& e : catalog)
      if (e.closed_manifold || e.need_repair) out.push_back(e);
    return out;
  }
  for (const char* name : {"dumbbell", "torus", "giraffe", "benchmark_a", "elephant", "knot1", "bones"})
    for (const auto& e : catalog)
      if (e.name == name) out.push_back(e);
  return out;
}

// Every mesh until it melts away: finite positions and valid topology throughout.
TEST(Stress, EveryMeshMeltsAwayValidly) {
  const bool full = full_run();
  const std::int64_t max_cycles = full ? 60000 : 6000;
  const std::int64_t intersect_every = full ? 250 : 500;
  std::ofstream csv(results_dir() / (full ? "stress_full.csv" : "stress_reduced.csv"));
  csv << "mesh,triangles,cycles,empty_at,topology_checks,intersection_checks,intersecting_checks,"
         "first_intersection_cycle,splits,seconds\n";
  const auto meshes = stress_meshes();
  ASSERT_FALSE(meshes.empty());
  for (const auto& e : meshes) {
    SCOPED_TRACE(e.name);
    const sim::IndexedMesh mesh = load_dataset(e);
    sim::MeltSimulator<double> s(sim::TriMesh<double>::from_indexed(mesh), default_params(mesh),
                                 sim::make_constant_kl(1.0), sim::Execution::kParallel);
    const auto t0 = std::chrono::steady_clock::now();
    std::int64_t c = 0, topo_checks = 0, si_checks = 0, si_hits = 0, first_si = -1, splits = 0;
    for (c = 1; c <= max_cycles && !s.empty(); ++c) {
      splits += s.step().repair_vertex_splits;
      if (c % 100 == 0 || s.empty()) {
        ++topo_checks;
        const sim::TopologyReport topo = sim::check_topology(s.mesh());
        ASSERT_TRUE(topo.valid()) << e.name << " cycle " << c << ": "
                                  << (topo.problems.empty() ? "counts" : topo.problems.front().describe());
        const auto& m = s.mesh();
        for (std::size_t v = 0; v < m.vertex_slots(); ++v) {
          if (m.vertex_alive[v]) {
            ASSERT_TRUE(m.position[v].allFinite()) << e.name << " cycle " << c << " v" << v;
          }
        }
      }
      if (c % intersect_every == 0 && !s.empty()) {
        ++si_checks;
        if (sim::self_intersections(s.mesh(), 1).intersects) {
          ++si_hits;
          if (first_si < 0) first_si = c;
        }
      }
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::int64_t empty_at = s.empty() ? c - 1 : -1;
    csv << fmt::format("{},{},{},{},{},{},{},{},{},{:.2f}\n", e.name, mesh.F.size(), c - 1, empty_at, topo_checks,
                       si_checks, si_hits, first_si, splits, seconds);
    csv.flush();
    if (full) {
      EXPECT_GE(empty_at, 0) << e.name << " did not melt away in " << max_cycles << " cycles";
    }
  }
}

// M_N alone against the combined displacement at the same initial melt rate: kN of the
// M_N-only run is scaled so that both lose the same volume in the first 50 cycles. Records
// the first cycle whose mesh intersects itself (sampled every `every` cycles).
struct FirstBreak {
  std::int64_t cycle = -1;  // -1: never within the run
  std::int64_t cycles_run = 0;
};

FirstBreak first_self_intersection(const sim::IndexedMesh& mesh, const sim::MeltParams& p, std::int64_t max_cycles,
                                   std::int64_t every) {
  sim::MeltSimulator<double> s(sim::TriMesh<double>::from_indexed(mesh), p, sim::make_constant_kl(1.0),
                               sim::Execution::kParallel);
  FirstBreak out;
  for (std::int64_t c = 1; c <= max_cycles && !s.empty(); ++c) {
    s.step();
    out.cycles_run = c;
    if (c % every == 0 && !s.empty() && sim::self_intersections(s.mesh(), 1).intersects) {
      out.cycle = c;
      return out;
    }
  }
  return out;
}

double volume_after(const sim::IndexedMesh& mesh, const sim::MeltParams& p, int cycles) {
  sim::MeltSimulator<double> s(sim::TriMesh<double>::from_indexed(mesh), p, sim::make_constant_kl(1.0),
                               sim::Execution::kParallel);
  for (int c = 0; c < cycles; ++c) s.step();
  return sim::mesh_volume(s.mesh());
}

TEST(Stress, NormalOnlyBreaksBeforeCombined) {
  const bool full = full_run();
  std::vector<std::string> names = {"dumbbell", "giraffe", "ship", "elephant"};
  if (full) names = {"dumbbell", "giraffe", "airplane", "ship", "warship", "elephant", "bunny00", "camel", "armadillo"};
  const std::int64_t max_cycles = full ? 20000 : 4000;
  const std::int64_t every = full ? 25 : 50;
  std::ofstream csv(results_dir() / (full ? "normal_vs_combined_full.csv" : "normal_vs_combined_reduced.csv"));
  csv << "mesh,triangles,kE,kN_combined,kN_normal_only,combined_first_intersection,combined_cycles,"
         "normal_first_intersection,normal_cycles,check_every\n";
  int normal_broke_first = 0, compared = 0;
  for (const auto& name : names) {
    SCOPED_TRACE(name);
    const sim::IndexedMesh mesh = load_dataset(datasets::dataset_entry(name));
    if (sim::self_intersections(sim::TriMesh<double>::from_indexed(mesh), 1).intersects) {
      csv << fmt::format("{},{},input intersects itself,,,,,,,\n", name, mesh.F.size());
      continue;  // both runs would "break" at the first check (e.g. CGAL's camel.off)
    }
    ++compared;
    sim::MeltParams combined = default_params(mesh);
    const double v0 = sim::mesh_volume(sim::TriMesh<double>::from_indexed(mesh));
    const double loss_combined = v0 - volume_after(mesh, combined, 50);
    sim::MeltParams normal = combined;
    normal.deform = sim::DeformMode::kNormalOnly;
    normal.kN = combined.kE;
    const double loss_normal = v0 - volume_after(mesh, normal, 50);
    ASSERT_GT(loss_normal, 0.0);
    normal.kN = combined.kE * loss_combined / loss_normal;  // same initial melt rate
    const FirstBreak fc = first_self_intersection(mesh, combined, max_cycles, every);
    const FirstBreak fn = first_self_intersection(mesh, normal, max_cycles, every);
    csv << fmt::format("{},{},{:.6g},{:.6g},{:.6g},{},{},{},{},{}\n", name, mesh.F.size(), combined.kE, combined.kN,
                       normal.kN, fc.cycle, fc.cycles_run, fn.cycle, fn.cycles_run, every);
    csv.flush();
    const std::int64_t c_break = fc.cycle < 0 ? max_cycles + 1 : fc.cycle;
    const std::int64_t n_break = fn.cycle < 0 ? max_cycles + 1 : fn.cycle;
    if (n_break < c_break) ++normal_broke_first;
  }
  // The monograph's claim (Figs. 3.1 vs 3.5): M_N alone breaks the mesh, the combination does
  // not (or much later). Required on most shapes rather than all: a shape with thin sheets
  // (the elephant's ears) intersects itself under both displacements within the first
  // sampled cycles, when the two sides of a sheet thinner than one step cross.
  ASSERT_GT(compared, 0);
  EXPECT_GE(4 * normal_broke_first, 3 * compared) << normal_broke_first << " of " << compared;
}

}  // namespace
}  // namespace meltlab
