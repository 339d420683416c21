#pragma once
// The stages of `meltlab reproduce` shared by its three files (internal to meltlab_experiments):
//   config.cpp    loading the experiment configs (variables, steps, content hash)
//   protocol.cpp  running one experiment into its folder: steps as child processes, logs, and
//                 the done.json marker that makes a finished folder reusable
//   schedule.cpp  the order and the workers, the experiments kept from earlier runs,
//                 summary.json and the report.
#include <meltlab/core/config.h>
#include <meltlab/core/process.h>
#include <meltlab/experiments/reproduce.h>
#include <meltlab/experiments/sweep.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace meltlab::experiments::reproduce_detail {

/// A progress line; the caller serializes the calls.
using Say = std::function<void(const std::string&)>;

/// The outcome recorded in `experiment`'s done.json if that marker exists, is readable and
/// carries `experiment.hash` (status left empty for the caller); nullopt otherwise (the folder
/// is then redone).
std::optional<ExperimentOutcome> read_finished(const ReproduceExperiment& experiment);

/// Runs the steps of `experiment` in order into a fresh folder; on success writes done.json
/// last. Fills `out` (status "ran" or "failed"). `stop` interrupts between steps.
void run_experiment(const ReproduceOptions& options, const ReproduceExperiment& experiment, ExperimentOutcome& out,
                    const Say& say, const std::atomic<bool>* stop);

/// How a step runs: its program and arguments, stdin from /dev/null, stdout to its stdout
/// file or logs/<step>.out, stderr to logs/<step>.err (the same locally and in a Slurm job).
ProcessSpec step_process(const ReproduceOptions& options, const ReproduceExperiment& experiment,
                         const ReproduceStep& step);

/// Progress counters of a run (the "[12.3s 2/5 done, 1 running, 0 failed]" prefix).
struct Counters {
  std::size_t finished = 0, running = 0, failed = 0;
};

/// The Slurm executor (slurm_executor.cpp): submits the experiments' steps as job chains and
/// arrays (or attaches to an earlier submission), waits for them unless options.slurm.detach,
/// and collects them into `outcomes` (one per experiment; "submitted" while they still run).
/// `say` is called with the counters up to date.
void run_on_slurm(const ReproduceOptions& options, const std::vector<ReproduceExperiment>& experiments,
                  std::vector<ExperimentOutcome>& outcomes, Counters& counters, const Say& say,
                  const std::atomic<bool>* stop);

/// The content hash of an experiment (config.cpp): config text, mode, version, arguments, files.
std::string content_hash(const ReproduceExperiment& experiment, const std::string& config_text,
                         const std::string& mode);
/// Fills the steps' depends_on and wave (rules in reproduce.h).
void find_waves(ReproduceExperiment& experiment);
/// A `slurm:` mapping of a config (partition, time, cpus, mem), checked.
SlurmResources slurm_section(const ConfigSection& section);

/// The steps of a sweep (sweep.cpp) appended to `experiment` (into its out_dir): one per point,
/// then collect and figures; its files added to the hashed ones. Waves and hash left to the caller.
void add_sweep_steps(const Sweep& sweep, const ReproduceOptions& options, ReproduceExperiment& experiment);

/// Steps as done.json and summary.json list them: [{name, exit_code, seconds}].
nlohmann::json steps_json(const std::vector<StepOutcome>& steps);

/// The last non-empty line of a text file ("" if unreadable): the error a failed step printed.
std::string last_line(const std::filesystem::path& file);

}  // namespace meltlab::experiments::reproduce_detail
