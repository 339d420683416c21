#include <meltlab/core/hash.h>
#include <meltlab/datasets/catalog.h>
#include <meltlab/experiments/simulate_run.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/sim/cgal/self_intersection.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/mesh_order.h>
#include <meltlab/sim/mesh_stats.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>
#include <meltlab/experiments/provenance.h>

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  const double f = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

}  // namespace

namespace {
template <class E>
std::string enum_name(E e, const std::vector<std::pair<E, const char*>>& names) {
  for (const auto& [v, n] : names)
    if (v == e) return n;
  return "?";
}
template <class E>
E enum_value(const json& j, const char* key, const std::vector<std::pair<E, const char*>>& names,
             const std::string& source) {
  const std::string s = j.at(key).get<std::string>();
  for (const auto& [v, n] : names)
    if (s == n) return v;
  throw InputError(fmt::format("{}: options.{}: unknown value '{}'", source, key, s));
}
const std::vector<std::pair<sim::DeformMode, const char*>> kDeformNames = {{sim::DeformMode::kCombined, "combined"},
                                                                           {sim::DeformMode::kNormalOnly, "normal"},
                                                                           {sim::DeformMode::kEdgeOnly, "edge"}};
const std::vector<std::pair<sim::TieRule, const char*>> kTieNames = {{sim::TieRule::kLessEqual, "le"},
                                                                     {sim::TieRule::kStrict, "strict"}};
const std::vector<std::pair<sim::EdgeSumMode, const char*>> kEdgeSumNames = {{sim::EdgeSumMode::kMean, "mean"},
                                                                             {sim::EdgeSumMode::kSum, "sum"}};
const std::vector<std::pair<sim::MergeMode, const char*>> kMergeNames = {
    {sim::MergeMode::kClusterMean, "cluster-mean"}, {sim::MergeMode::kSequentialPairwise, "pairwise"}};
}  // namespace

json options_to_json(const SimulateOptions& o) {
  json j = {{"mesh", o.mesh},
            {"cycles", o.cycles},
            {"stop_when_empty", o.stop_when_empty},
            {"kg", o.kg},
            {"kE", o.kE},
            {"kr", o.kr},
            {"relative_units", o.relative_units},
            {"deform", enum_name(o.deform, kDeformNames)},
            {"tie", enum_name(o.tie, kTieNames)},
            {"edge_sum", enum_name(o.edge_sum, kEdgeSumNames)},
            {"merge", enum_name(o.merge, kMergeNames)},
            {"repair_topology", o.repair_topology},
            {"remnant_check_every", o.remnant_check_every},
            {"compact_below", o.compact_below},
            {"compact_after", o.compact_after},
            {"kl_file", o.kl_file.string()},
            {"double_precision", o.double_precision},
            {"order", o.order},
            {"weld_tolerance", o.load.weld_tolerance},
            {"repair_input", o.load.repair}};
  if (o.kN) j["kN"] = *o.kN;
  return j;
}

SimulateOptions options_from_json(const json& j, const std::string& source) {
  SimulateOptions o;
  try {
    o.mesh = j.at("mesh").get<std::string>();
    o.cycles = j.at("cycles").get<std::int64_t>();
    o.stop_when_empty = j.at("stop_when_empty").get<bool>();
    o.kg = j.at("kg").get<double>();
    o.kE = j.at("kE").get<double>();
    if (j.contains("kN")) o.kN = j.at("kN").get<double>();
    o.kr = j.at("kr").get<double>();
    o.relative_units = j.at("relative_units").get<bool>();
    o.deform = enum_value(j, "deform", kDeformNames, source);
    o.tie = enum_value(j, "tie", kTieNames, source);
    o.edge_sum = enum_value(j, "edge_sum", kEdgeSumNames, source);
    o.merge = enum_value(j, "merge", kMergeNames, source);
    o.repair_topology = j.at("repair_topology").get<bool>();
    o.remnant_check_every = j.at("remnant_check_every").get<int>();
    o.compact_below = j.at("compact_below").get<double>();
    // Run folders before compact_after compacted by compact_below only (the melt is the same).
    o.compact_after = j.value("compact_after", 0.0);
    o.kl_file = j.at("kl_file").get<std::string>();
    o.double_precision = j.at("double_precision").get<bool>();
    // Run folders before the breadth-first order stored a flag.
    o.order =
        j.contains("order") ? j.at("order").get<std::string>() : (j.at("morton_order").get<bool>() ? "morton" : "file");
    o.load.weld_tolerance = j.at("weld_tolerance").get<double>();
    o.load.repair = j.at("repair_input").get<bool>();
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: run options incomplete or malformed: {}", source, e.what()));
  }
  return o;
}

fs::path resolve_mesh_argument(const std::string& mesh) {
  std::error_code ec;
  if (fs::exists(mesh, ec)) return mesh;
  const bool looks_like_path = mesh.find('/') != std::string::npos || mesh.find('.') != std::string::npos;
  try {
    return datasets::dataset_path(mesh);
  } catch (const InputError& e) {
    if (looks_like_path) throw InputError(fmt::format("{}: no such file", mesh));
    throw InputError(
        fmt::format("{}: neither a mesh file nor a dataset ({}); see `meltlab dataset list`", mesh, e.what()));
  }
}

std::unique_ptr<PreparedSimulation> prepare_simulation(const SimulateOptions& o, bool check_output) {
  auto p = std::make_unique<PreparedSimulation>();
  p->opt = o;
  require(o.cycles >= 0, fmt::format("--cycles: must be >= 0 (got {})", o.cycles));
  require(o.snapshot_every >= 0, "--snapshot-every: must be >= 0");
  require(o.stats_every >= 1, "--stats-every: must be >= 1");
  require(o.order == "morton" || o.order == "bfs" || o.order == "file", "--order: must be morton, bfs or file");
  require(o.check_every >= 0, "--check-every: must be >= 0");
  require(o.intersect_every >= 0, "--check-intersections-every: must be >= 0");
  require(o.threads >= 0, "--threads: must be >= 0");
  require(sim::mesh_format_of("x." + o.snapshot_format) == o.snapshot_format &&
              (o.snapshot_format == "ply" || o.snapshot_format == "off" || o.snapshot_format == "obj" ||
               o.snapshot_format == "stl"),
          fmt::format("--snapshot-format: '{}' is not one of ply, off, obj, stl", o.snapshot_format));
  p->mesh_path = fs::absolute(resolve_mesh_argument(o.mesh));
  if (!o.kl_file.empty()) p->opt.kl_file = fs::absolute(o.kl_file);
  p->loaded = sim::load_mesh(p->mesh_path, o.load);
  p->mesh = o.order == "morton" ? sim::reorder_for_locality(p->loaded.mesh).mesh
            : o.order == "bfs"  ? sim::reorder_breadth_first(p->loaded.mesh).mesh
                                : p->loaded.mesh;
  const auto tm = sim::TriMesh<double>::from_indexed(p->mesh);
  const sim::QualityReport q = sim::mesh_quality(tm);
  p->mean_edge_length = q.mean_edge_length;

  // Coefficients: relative units scale with the input's mean edge length L0.
  const double scale = p->coefficient_unit();
  auto checked = [](double x, const char* name) {
    if (!std::isfinite(x) || x < 0) throw InputError(fmt::format("{}: must be a finite number >= 0 (got {})", name, x));
    return x;
  };
  p->params.kg = o.kg;
  p->params.kE = checked(o.kE, "--ke") * scale;
  p->params.kN = checked(o.kN.value_or(o.kE / 100.0), "--kn") * scale;
  p->params.kr = checked(o.kr, "--kr") * scale;
  p->params.deform = o.deform;
  p->params.tie = o.tie;
  p->params.edge_sum = o.edge_sum;
  p->params.merge = o.merge;
  p->params.repair = o.repair_topology;
  p->params.remnant_check_every = o.remnant_check_every;
  p->params.compact_below = o.compact_below;
  p->params.compact_after = o.compact_after;
  try {
    p->params.validate();
  } catch (const InputError& e) {
    // "compact_after: ..." names the parameter; the option is --compact-after (kE: --ke).
    std::string what = e.what();
    const std::size_t colon = what.find(':');
    if (colon == std::string::npos) throw InputError("--" + what);  // no name to map: as it is
    for (std::size_t i = 0; i < colon; ++i)
      what[i] = what[i] == '_' ? '-' : static_cast<char>(std::tolower(static_cast<unsigned char>(what[i])));
    throw InputError("--" + what);
  }

  sim::KlContext ctx;
  ctx.bbox_min = q.bbox_min;
  ctx.bbox_max = q.bbox_max;
  p->kl = o.kl_file.empty() ? sim::make_constant_kl(1.0) : sim::load_kl_field(p->opt.kl_file, ctx);

  const auto& r = p->loaded.report;
  p->mesh_json = {
      {"argument", o.mesh},
      {"file", p->mesh_path.string()},
      {"file_hash", file_hash(p->mesh_path)},
      {"file_vertices", r.file_vertices},
      {"file_faces", r.file_faces},
      {"welded_vertices", r.welded_vertices},
      {"unreferenced_vertices", r.unreferenced_vertices},
      {"degenerate_faces", r.degenerate_faces},
      {"repairs", r.repairs},
      {"vertices", p->mesh.V.size()},
      {"triangles", p->mesh.F.size()},
      {"mean_edge_length", q.mean_edge_length},
      {"volume", q.volume},
      {"area", q.area},
      {"bbox_min", {q.bbox_min.x(), q.bbox_min.y(), q.bbox_min.z()}},
      {"bbox_max", {q.bbox_max.x(), q.bbox_max.y(), q.bbox_max.z()}},
      {"order", o.order},
  };
  // The output folder last among the checks of the arguments, first before any work is written.
  if (check_output) p->output.emplace(o.out_dir, RunFolderOptions{"--out", "run.json", "run", o.overwrite});
  return p;
}

namespace {

struct StatsWriter {
  fs::path target, tmp;
  std::ofstream out;
  sim::MeshStatistics stats;  // its buffers are reused by every row
  explicit StatsWriter(const fs::path& file) : target(file), tmp(temporary_path_for(file)) {
    out.open(tmp, std::ios::trunc);
    if (!out) throw InputError(fmt::format("{}: cannot open for writing", target.string()));
    out << "cycle,vertices,triangles,components,euler,genus,volume,area,Qs,Qd,Qq,max_d,ms,"
           "merged,glued,repair_splits,repair_collapses,inverted_removed,deform_ms,collapse_ms,glued_ms,repair_ms\n";
  }
  /// Writes the row; returns the statistics' time in ms (not the CSV formatting).
  template <class Real>
  double row(std::int64_t cycle, const sim::TriMesh<Real>& m, const sim::CycleReport& r, double ms) {
    const auto t0 = std::chrono::steady_clock::now();
    const sim::MeshStats& st = stats.compute(m);
    const double stats_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const sim::EulerCounts& topo = st.topology;
    const sim::QualityReport& q = st.quality;
    out << fmt::format(
        "{},{},{},{},{},{},{:.9g},{:.9g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{},{},{},{:.4g},{:.4g},{:.4g},{:.4g}"
        "\n",
        cycle, topo.V, topo.F, topo.S, topo.chi, topo.G, q.volume, q.area, q.Qs, q.Qd, q.Qq, q.max_d, ms,
        r.merged_vertices, r.glued_triangles, r.repair_vertex_splits, r.repair_edge_collapses, r.inverted_parts_removed,
        r.deform_ms, r.collapse_ms, r.glued_ms, r.repair_ms);
    return stats_ms;
  }
  void finish() {
    out.flush();
    if (!out) throw InputError(fmt::format("{}: write failed (disk full?)", target.string()));
    out.close();
    fs::rename(tmp, target);
  }
  ~StatsWriter() {
    if (out.is_open()) {
      out.close();
      std::error_code ec;
      fs::remove(tmp, ec);
    }
  }
};

// The checks of a run (--check-every, --check-intersections-every) and what they found.
struct RunChecks {
  std::int64_t topology_checks = 0, intersection_checks = 0, first_intersection = -1;
  json intersections = json::array();

  // Throws InvariantError on an invalid mesh.
  template <class Real>
  void check_topology(std::int64_t cycle, const sim::TriMesh<Real>& mesh) {
    ++topology_checks;
    const sim::TopologyReport topo = sim::check_topology(mesh);
    if (!topo.valid())
      throw InvariantError(
          fmt::format("cycle {}: invalid topology: {}", cycle,
                      topo.problems.empty() ? "Euler counts inconsistent" : topo.problems.front().describe()));
  }
  template <class Real>
  void check_intersections(std::int64_t cycle, const sim::TriMesh<Real>& mesh, std::int64_t triangles) {
    const sim::SelfIntersectionReport si = sim::self_intersections(mesh, 1000);
    intersections.push_back({{"cycle", cycle}, {"intersecting_pairs", si.pairs}, {"triangles", triangles}});
    if (si.intersects && first_intersection < 0) first_intersection = cycle;
  }
  json to_json(const SimulateOptions& o) const {
    return {{"topology_every", o.check_every},
            {"topology_checks", topology_checks},
            {"intersections_every", o.intersect_every},
            {"intersection_checks", intersection_checks},
            {"first_self_intersection_cycle", first_intersection},
            {"intersections", intersections}};
  }
};

// The time of each cycle and of each pass (excluding statistics, checks and snapshots).
struct CycleTimes {
  std::vector<double> cycle_ms;
  double pass_ms[6] = {0, 0, 0, 0, 0, 0};  ///< sums: deform, collapse, glued, repair, remnant check, compaction
  std::int64_t compactions = 0;
  /// The statistics' time of each row: a run spends it beside the cycles (with a row every
  /// cycle, several times the cycle's own time).
  std::vector<double> stats_ms;

  void add(const sim::CycleReport& r, double ms) {
    cycle_ms.push_back(ms);
    pass_ms[0] += r.deform_ms, pass_ms[1] += r.collapse_ms, pass_ms[2] += r.glued_ms, pass_ms[3] += r.repair_ms;
    pass_ms[4] += r.remnant_ms, pass_ms[5] += r.compact_ms;
    compactions += r.compacted ? 1 : 0;
  }
  json to_json(double total_s) const {
    const auto n = static_cast<double>(std::max<std::size_t>(1, cycle_ms.size()));
    return {{"total_s", total_s},
            {"cycle_ms_mean", cycle_ms.empty() ? 0.0 : std::accumulate(cycle_ms.begin(), cycle_ms.end(), 0.0) / n},
            {"cycle_ms_median", percentile(cycle_ms, 0.5)},
            {"cycle_ms_p95", percentile(cycle_ms, 0.95)},
            {"cycle_ms_max", cycle_ms.empty() ? 0.0 : *std::max_element(cycle_ms.begin(), cycle_ms.end())},
            {"pass_ms_mean",
             {{"deform", pass_ms[0] / n},
              {"collapse", pass_ms[1] / n},
              {"glued", pass_ms[2] / n},
              {"repair", pass_ms[3] / n},
              {"remnant_check", pass_ms[4] / n},
              {"compaction", pass_ms[5] / n}}},
            {"compactions", compactions},
            {"stats_rows", stats_ms.size()},
            {"stats_row_ms_median", percentile(stats_ms, 0.5)},
            {"stats_ms_total", std::accumulate(stats_ms.begin(), stats_ms.end(), 0.0)},
            {"note",
             "cycle times exclude statistics, checks and snapshots; stats_row_ms is the time of "
             "one statistics row (MeshStatistics), stats_ms_total of all of them"}};
  }
};

// The resolved melt parameters and the open choices of the model, for run.json.
json parameters_json(const PreparedSimulation& p) {
  const SimulateOptions& o = p.opt;
  return {
      {"kg", p.params.kg},
      {"kE", p.params.kE},
      {"kN", p.params.kN},
      {"kr", p.params.kr},
      {"units", o.relative_units ? "relative to L0" : "absolute"},
      {"L0_mean_edge_length", p.mean_edge_length},
      {"as_given", {{"kg", o.kg}, {"kE", o.kE}, {"kN", o.kN.value_or(o.kE / 100.0)}, {"kr", o.kr}}},
      {"deform", enum_name(o.deform, kDeformNames)},
      {"sign_test_tie", o.tie == sim::TieRule::kLessEqual ? "<= (Alg. 1)" : "< (Eq. 3.6)"},
      {"M_E_mode", o.edge_sum == sim::EdgeSumMode::kMean ? "mean" : "sum"},
      {"merge_position_mode", o.merge == sim::MergeMode::kClusterMean ? "cluster_mean" : "sequential_pairwise"},
      {"reindex_conflict_policy", "smallest target"},
      {"edge_test_order", "ab, bc, ca; at most one edge per triangle per pass"},
      {"zero_guard", "zero vectors contribute nothing"},
      {"orphan_vertex_policy", "deleted"},
      {"topology_repair", o.repair_topology},
      {"remnant_check_every", p.params.remnant_check_every},
      {"compact_below", p.params.compact_below},
      {"compact_after", p.params.compact_after},
      {"initial_sort", "rotate min-index first before cycle 1"},
      {"glued_detection", "vertex count 2 (Alg. 3) + link test in the repair"},
      {"kl", json::parse(p.kl->describe_json())},
      {"kl_file", p.opt.kl_file.string()},
      {"kl_file_hash", p.opt.kl_file.empty() ? std::string() : file_hash(p.opt.kl_file)},
  };
}

// run.json without the error and the provenance.
template <class Real>
json run_record(const PreparedSimulation& p, const SimulateResult& result, const sim::TriMesh<Real>& final_mesh,
                int threads, sim::Execution exec, std::int64_t inverted_removed, const CycleTimes& times,
                double total_s, const RunChecks& checks, const std::vector<std::string>& snapshots) {
  const SimulateOptions& o = p.opt;
  return {
      {"options", options_to_json(p.opt)},
      {"status", result.status},
      {"mesh", p.mesh_json},
      {"parameters", parameters_json(p)},
      {"precision", std::is_same_v<Real, float> ? "float" : "double"},
      {"threads", threads},
      {"execution", exec == sim::Execution::kSerial ? "serial" : "parallel"},
      {"cycles_requested", o.cycles},
      {"cycles_run", result.cycles_run},
      {"empty_at_cycle", result.empty_at_cycle},
      {"final", {{"vertices", final_mesh.live_vertex_count()}, {"triangles", final_mesh.live_triangle_count()}}},
      {"inverted_parts_removed", inverted_removed},
      {"timing", times.to_json(total_s)},
      {"checks", checks.to_json(o)},
      {"outputs", {{"stats", "stats.csv"}, {"snapshots", snapshots}}},
      {"stats_every", o.stats_every},
  };
}

template <class Real>
SimulateResult run_typed(PreparedSimulation& p, const std::function<void(const SimulateProgress&)>& progress,
                         const std::atomic<bool>* stop) {
  const SimulateOptions& o = p.opt;
  if (!p.output) throw InvariantError("run_simulation: the simulation was prepared without an output folder");
  const fs::path dir = p.output->path();
  Provenance provenance = start_provenance("simulate", o.command_line);
  create_output_directories(dir / "snapshots", "--out");
  const int threads = o.threads == 0 ? tbb::info::default_concurrency() : o.threads;
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  const sim::Execution exec = threads == 1 ? sim::Execution::kSerial : sim::Execution::kParallel;

  sim::MeltSimulator<Real> simulator(sim::TriMesh<Real>::from_indexed(p.mesh), p.params, p.kl, exec);
  StatsWriter stats(dir / "stats.csv");
  const int width = std::max(6, static_cast<int>(std::to_string(o.cycles).size()));
  std::vector<std::string> snapshots;
  auto snapshot = [&](std::int64_t cycle) {
    const std::string name = fmt::format("cycle_{:0{}}.{}", cycle, width, o.snapshot_format);
    sim::save_mesh(simulator.mesh().to_indexed(), dir / "snapshots" / name);
    snapshots.push_back("snapshots/" + name);
  };

  // ---- cycle 0 ----
  SimulateResult result;
  result.status = "completed";
  CycleTimes times;
  times.cycle_ms.reserve(static_cast<std::size_t>(std::min<std::int64_t>(o.cycles, 1 << 20)));
  std::int64_t inverted_removed = 0;
  RunChecks checks;
  if (o.intersect_every > 0)
    checks.check_intersections(0, simulator.mesh(), static_cast<std::int64_t>(simulator.mesh().live_triangle_count()));
  sim::CycleReport last;
  times.stats_ms.push_back(stats.row(0, simulator.mesh(), last, 0.0));
  snapshot(0);

  // ---- the cycles: step, statistics, checks, snapshots, progress ----
  bool last_row_written = true, last_snapshot_written = true;
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  auto t_progress = t_start;
  std::int64_t c = 0;
  try {
    for (c = 1; c <= o.cycles; ++c) {
      if (stop && stop->load()) {
        result.status = "interrupted";
        --c;
        break;
      }
      const auto t0 = Clock::now();
      last = simulator.step();
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      times.add(last, ms);
      inverted_removed += last.inverted_parts_removed;
      const bool empty = last.live_triangles == 0;
      last_row_written = last_snapshot_written = false;
      if (c % o.stats_every == 0 || empty) {
        times.stats_ms.push_back(stats.row(c, simulator.mesh(), last, ms));
        last_row_written = true;
      }
      if (o.check_every > 0 && (c % o.check_every == 0 || empty)) checks.check_topology(c, simulator.mesh());
      if (o.intersect_every > 0 && (c % o.intersect_every == 0)) {
        ++checks.intersection_checks;
        checks.check_intersections(c, simulator.mesh(), static_cast<std::int64_t>(last.live_triangles));
      }
      if (o.snapshot_every > 0 && c % o.snapshot_every == 0) {
        snapshot(c);
        last_snapshot_written = true;
      }
      if (progress && (Clock::now() - t_progress > std::chrono::milliseconds(100))) {
        t_progress = Clock::now();
        progress({c, o.cycles, last.live_triangles,
                  std::chrono::duration<double, std::milli>(t_progress - t_start).count() / static_cast<double>(c)});
      }
      if (empty) {
        result.empty_at_cycle = c;
        if (o.stop_when_empty) {
          result.status = "melted";
          break;
        }
      }
    }
    if (c > o.cycles) c = o.cycles;
  } catch (const InvariantError& e) {
    result.status = "failed";
    result.error = e.what();
  }

  // ---- the last row and snapshot, run.json ----
  result.cycles_run = c;
  if (!last_row_written && c > 0)
    times.stats_ms.push_back(
        stats.row(c, simulator.mesh(), last, times.cycle_ms.empty() ? 0.0 : times.cycle_ms.back()));
  if (!last_snapshot_written) snapshot(c);
  stats.finish();
  if (progress) progress({c, o.cycles, last.live_triangles, 0.0});
  const double total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  provenance.timings_s.emplace_back("cycles", total_s);
  json run =
      run_record(p, result, simulator.mesh(), threads, exec, inverted_removed, times, total_s, checks, snapshots);
  if (!result.error.empty()) run["error"] = result.error;
  result.run_json = commit_run(*p.output, std::move(run), provenance);
  return result;
}

}  // namespace

SimulateResult run_simulation(PreparedSimulation& prepared,
                              const std::function<void(const SimulateProgress&)>& progress,
                              const std::atomic<bool>* stop) {
  if (prepared.opt.double_precision) return run_typed<double>(prepared, progress, stop);
  return run_typed<float>(prepared, progress, stop);
}

}  // namespace meltlab::experiments
