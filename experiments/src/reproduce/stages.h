#pragma once
// The stages of `meltlab reproduce` shared by its three files (internal to meltlab_experiments):
//   config.cpp    loading the experiment configs (variables, steps, content hash)
//   protocol.cpp  running one experiment into its folder: steps as child processes, logs, and
//                 the done.json marker that makes a finished folder reusable
//   schedule.cpp  the order and the workers, the experiments kept from earlier runs,
//                 summary.json and the report.
#include <meltlab/experiments/reproduce.h>

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

/// Steps as done.json and summary.json list them: [{name, exit_code, seconds}].
nlohmann::json steps_json(const std::vector<StepOutcome>& steps);

/// The last non-empty line of a text file ("" if unreadable): the error a failed step printed.
std::string last_line(const std::filesystem::path& file);

}  // namespace meltlab::experiments::reproduce_detail
