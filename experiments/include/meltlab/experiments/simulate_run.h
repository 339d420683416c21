#pragma once
// `meltlab simulate`: runs the melt cycle on a mesh and writes the run folder
//   DIR/stats.csv         one row per recorded cycle (cycle 0 = the input)
//   DIR/snapshots/*.ply   mesh snapshots (cycle 0, every K cycles, and the last cycle)
//   DIR/run.json          parameters (as given and resolved), timings, result, provenance
// Every input is validated before DIR is touched; every file is written atomically.

#include <meltlab/core/run_folder.h>
#include <meltlab/sim/melt.h>
#include <meltlab/sim/mesh_io.h>

#include <nlohmann/json.hpp>

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct SimulateOptions {
  std::string mesh;             ///< a mesh file, or a dataset name from the catalog
  std::int64_t cycles = 1000;   ///< maximum number of cycles
  bool stop_when_empty = true;  ///< stop once every triangle has melted
  // Coefficients. With relative units, kE, kN and kr are multiples of the input's mean edge
  // length L0 (kE, kN per cycle); with absolute units they are in mesh units.
  double kg = 1.0;
  double kE = 0.05;
  std::optional<double> kN;  ///< default kE / 100 (the monograph's kE ≈ 100 kN)
  double kr = 0.5;
  bool relative_units = true;
  sim::DeformMode deform = sim::DeformMode::kCombined;
  sim::TieRule tie = sim::TieRule::kLessEqual;
  sim::EdgeSumMode edge_sum = sim::EdgeSumMode::kMean;
  sim::MergeMode merge = sim::MergeMode::kClusterMean;
  bool repair_topology = true;
  int remnant_check_every = 16;   ///< see sim::MeltParams::remnant_check_every
  double compact_below = 0.5;     ///< see sim::MeltParams::compact_below
  double compact_after = 1.0;     ///< see sim::MeltParams::compact_after
  std::filesystem::path kl_file;  ///< YAML with a top-level `kl:`; empty = constant 1
  bool double_precision = true;
  int threads = 0;               ///< 0 = all cores; 1 = serial execution
  std::string order = "morton";  ///< vertex numbering: morton, bfs (breadth-first after morton) or file
  sim::LoadOptions load;
  std::int64_t snapshot_every = 0;  ///< 0 = first and last only
  std::string snapshot_format = "ply";
  std::int64_t stats_every = 1;      ///< stats row every K cycles (and the last)
  std::int64_t check_every = 0;      ///< full topology check every K cycles (0 = never); fails the run if invalid
  std::int64_t intersect_every = 0;  ///< CGAL self-intersection test every K cycles (0 = never)
  std::filesystem::path out_dir;
  bool overwrite = false;                 ///< allow DIR to hold a previous run
  std::vector<std::string> command_line;  ///< argv, recorded in run.json's provenance
};

struct SimulateProgress {
  std::int64_t cycle = 0, cycles = 0, triangles = 0;
  double ms_per_cycle = 0;
};

struct SimulateResult {
  std::string status;  ///< completed | melted | interrupted | failed
  std::int64_t cycles_run = 0;
  std::int64_t empty_at_cycle = -1;  ///< first cycle after which no triangle was left
  nlohmann::json run_json;
  std::string error;  ///< for status failed
};

/// A validated simulation: the loaded (and possibly renumbered) mesh and resolved parameters.
struct PreparedSimulation {
  SimulateOptions opt;
  std::filesystem::path mesh_path;
  sim::LoadedMesh loaded;
  sim::IndexedMesh mesh;        ///< as melted (renumbered unless order is file)
  double mean_edge_length = 0;  ///< L0 of the input, mesh units
  /// Mesh units per unit of the --ke/--kn/--kr options: L0 with relative units, else 1.
  double coefficient_unit() const { return opt.relative_units ? mean_edge_length : 1.0; }
  sim::MeltParams params;  ///< absolute units
  sim::KlFieldPtr kl;
  nlohmann::json mesh_json;
  std::optional<RunFolder> output;  ///< the run folder (prepared with check_output)
};

/// Validates everything (mesh, kl file, numbers, output folder) and throws InputError on
/// the first problem, before anything is written. `check_output` = false skips the output
/// folder checks (for replaying a finished run).
std::unique_ptr<PreparedSimulation> prepare_simulation(const SimulateOptions& options, bool check_output = true);

/// The options as JSON (recorded in run.json as "options") and back. Paths are absolute.
nlohmann::json options_to_json(const SimulateOptions& options);
SimulateOptions options_from_json(const nlohmann::json& j, const std::string& source);

/// Runs a prepared simulation. `progress` is called about ten times a second; `stop` is
/// polled every cycle (set it from a signal handler to interrupt: status "interrupted").
/// A run that breaks an invariant ends with status "failed" and still writes its outputs.
SimulateResult run_simulation(PreparedSimulation& prepared,
                              const std::function<void(const SimulateProgress&)>& progress,
                              const std::atomic<bool>* stop = nullptr);

/// Resolves a --mesh argument: an existing file, else a catalog dataset (fetched/cached).
std::filesystem::path resolve_mesh_argument(const std::string& mesh);

}  // namespace meltlab::experiments
