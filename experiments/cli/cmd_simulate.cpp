// meltlab simulate: run the melt cycle on a mesh (monograph chapter 3).

#include <meltlab/experiments/simulate_run.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "cli_util.h"
#include "commands.h"
#include "melt_options.h"

namespace meltlab::cli {

Run add_simulate(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub =
      app.add_subcommand("simulate", "Melt a mesh with the empirical surface model (Alg. 1-3) and record every cycle");
  auto o = std::make_shared<experiments::SimulateOptions>();
  auto order = std::make_shared<std::string>("morton");
  auto no_repair = std::make_shared<bool>(false);
  auto keep_going = std::make_shared<bool>(false);
  o->command_line = command_line;

  sub->add_option("--mesh", o->mesh, "Mesh file (.off .ply .obj .stl) or a dataset name (meltlab dataset list)")
      ->required();
  sub->add_option("--cycles", o->cycles, "Number of cycles (stops earlier when everything has melted)")
      ->default_val(1000);
  sub->add_option("--out", o->out_dir, "Output folder (stats.csv, run.json, snapshots/)")->required();
  MeltOptionSet melt;
  melt.threads = true;
  const auto store_melt_options = add_melt_options(*sub, *o, melt);
  std::map<std::string, sim::DeformMode> deform{{"combined", sim::DeformMode::kCombined},
                                                {"normal", sim::DeformMode::kNormalOnly},
                                                {"edge", sim::DeformMode::kEdgeOnly}};
  sub->add_option("--deform", o->deform,
                  "Displacement: combined (Eq. 3.6), normal (M_N only, Fig. 3.1), edge (M_E only)")
      ->transform(CLI::CheckedTransformer(deform, CLI::ignore_case))
      ->default_str("combined");
  std::map<std::string, sim::TieRule> tie{{"le", sim::TieRule::kLessEqual}, {"strict", sim::TieRule::kStrict}};
  sub->add_option("--tie", o->tie, "N.M_E = 0 takes the combined branch (le, Alg. 1) or not (strict, Eq. 3.6)")
      ->transform(CLI::CheckedTransformer(tie, CLI::ignore_case))
      ->default_str("le");
  std::map<std::string, sim::EdgeSumMode> edge_sum{{"mean", sim::EdgeSumMode::kMean}, {"sum", sim::EdgeSumMode::kSum}};
  sub->add_option("--edge-sum", o->edge_sum, "M_E as the mean (Alg. 1) or sum (Eq. 3.5) of the unit edge vectors")
      ->transform(CLI::CheckedTransformer(edge_sum, CLI::ignore_case))
      ->default_str("mean");
  std::map<std::string, sim::MergeMode> merge{{"cluster-mean", sim::MergeMode::kClusterMean},
                                              {"pairwise", sim::MergeMode::kSequentialPairwise}};
  sub->add_option("--merge", o->merge,
                  "Merged position: cluster-mean (order-independent, GPU 5.4) or pairwise (CPU Alg. 2)")
      ->transform(CLI::CheckedTransformer(merge, CLI::ignore_case))
      ->default_str("cluster-mean");
  sub->add_option("--remnant-check-every", o->remnant_check_every,
                  "Every K cycles delete parts whose volume is <= 0 (inverted remnants; 0 = never)")
      ->default_val(16);
  sub->add_option(
         "--compact-below", o->compact_below,
         "Compact the arrays when fewer than this fraction of triangle slots is live (0 = never, as the monograph)")
      ->default_val(0.5);
  sub->add_option("--compact-after", o->compact_after,
                  "Also compact once the dead fraction of the triangle slots, summed over the cycles since the last "
                  "compaction, reaches this (about what the dead slots cost against one compaction; 0 = by "
                  "--compact-below only). Compaction never changes the melt")
      ->default_val(1.0);
  sub->add_flag("--no-repair", *no_repair,
                "Do not run the topology repair after Alg. 3 (the monograph's algorithms only)");
  sub->add_option("--order", *order,
                  "Vertex numbering: morton (renumbered for locality), bfs (breadth-first over the surface after "
                  "morton: neighbours closer in memory, faster cycles on meshes beyond the caches) or file (as in "
                  "the input). The numbering decides Alg. 2's ties, so each melts to its own valid result")
      ->check(CLI::IsMember({"morton", "bfs", "file"}))
      ->default_val("morton");
  sub->add_option("--snapshot-every", o->snapshot_every, "Write the mesh every K cycles (0 = first and last only)")
      ->default_val(0);
  sub->add_option("--snapshot-format", o->snapshot_format, "Snapshot file format: ply, off, obj, stl")
      ->default_val("ply");
  sub->add_option("--stats-every", o->stats_every, "Write a stats.csv row every K cycles")->default_val(1);
  sub->add_option("--check-every", o->check_every,
                  "Full topology check every K cycles; the run fails if it breaks (0 = off)")
      ->default_val(0);
  sub->add_option("--check-intersections-every", o->intersect_every,
                  "CGAL self-intersection test every K cycles, recorded in run.json (0 = off)")
      ->default_val(0);
  sub->add_flag("--keep-going", *keep_going, "Keep cycling after the mesh has melted away");
  sub->add_option("--weld-tol", o->load.weld_tolerance, "Merge input vertices closer than this (mesh units)")
      ->default_val(0.0);
  sub->add_flag("--repair", o->load.repair, "Repair open/non-manifold input with CGAL instead of refusing it");
  sub->add_flag("--overwrite", o->overwrite, "Allow --out to hold a previous run");

  return [=]() {
    store_melt_options();
    o->order = *order;
    o->repair_topology = !*no_repair;
    o->stop_when_empty = !*keep_going;
    auto prepared = experiments::prepare_simulation(*o);
    std::fprintf(stderr,
                 "meltlab: %s: %zu vertices, %zu triangles, L0 = %.4g; kE = %.4g, kN = %.4g, kr = %.4g (mesh units)\n",
                 prepared->mesh_path.string().c_str(), prepared->mesh.V.size(), prepared->mesh.F.size(),
                 prepared->mean_edge_length, prepared->params.kE, prepared->params.kN, prepared->params.kr);
    InterruptScope interrupt;
    ProgressLine line;
    const auto result = experiments::run_simulation(
        *prepared,
        [&](const experiments::SimulateProgress& p) {
          line.update(p.cycle, p.cycles,
                      fmt::format("cycles  {} triangles  {:.3f} ms/cycle", p.triangles, p.ms_per_cycle));
        },
        interrupt.flag());
    line.finish();
    const auto& t = result.run_json["timing"];
    std::fprintf(stderr,
                 "meltlab: %s after %lld cycles (%lld triangles left); median %.3f ms/cycle, %.3f ms per statistics "
                 "row; wrote %s\n",
                 result.status.c_str(), static_cast<long long>(result.cycles_run),
                 result.run_json["final"]["triangles"].get<long long>(), t["cycle_ms_median"].get<double>(),
                 t["stats_row_ms_median"].get<double>(), o->out_dir.string().c_str());
    const double stats_share = t["stats_ms_total"].get<double>() / std::max(1e-9, 1e3 * t["total_s"].get<double>());
    if (stats_share > 0.5 && o->stats_every == 1)
      std::fprintf(stderr, "meltlab: the statistics rows took %.0f %% of the run; --stats-every K writes every K-th\n",
                   100.0 * stats_share);
    if (result.status == "failed") {
      std::fprintf(stderr, "meltlab: internal error: %s\n", result.error.c_str());
      return kExitInternal;
    }
    if (result.status == "interrupted") return kExitInterrupted;
    return kExitOk;
  };
}

}  // namespace meltlab::cli
