#pragma once
// Every subcommand registers itself on the app and returns the function that runs it.

#include <meltlab/experiments/reproduce.h>

#include <CLI/CLI.hpp>

#include <filesystem>

#include <functional>
#include <string>
#include <vector>

namespace meltlab::cli {

using Run = std::function<int()>;

Run add_simulate(CLI::App& app, const std::vector<std::string>& command_line);
Run add_mesh_info(CLI::App& app);
Run add_dataset(CLI::App& app);
Run add_compare(CLI::App& app, const std::vector<std::string>& command_line);
Run add_synth_sequence(CLI::App& app, const std::vector<std::string>& command_line);
Run add_fit(CLI::App& app, const std::vector<std::string>& command_line);
Run add_manufacture(CLI::App& app, const std::vector<std::string>& command_line);
Run add_predict(CLI::App& app, const std::vector<std::string>& command_line);
Run add_render(CLI::App& app, const std::vector<std::string>& command_line);
Run add_reproduce(CLI::App& app);
Run add_volume(CLI::App& app, const std::vector<std::string>& command_line);
Run add_fog(CLI::App& app, const std::vector<std::string>& command_line);
Run add_sweep(CLI::App& app, const std::vector<std::string>& command_line);
Run add_run_job(CLI::App& app, const std::vector<std::string>& command_line);

/// The executor options shared by reproduce and sweep (--executor, the Slurm resources, --detach).
void add_executor_options(CLI::App& sub, experiments::ReproduceOptions& options);
/// The Slurm waves of an experiment with their resources (--list --executor slurm).
void print_waves(const experiments::ReproduceExperiment& experiment, const experiments::SlurmOptions& slurm);
/// The outcome table and summary lines of a reproduce run; returns the exit code.
int print_outcome(const experiments::ReproduceResult& result, const std::filesystem::path& out_dir);
/// Runs the experiments (Ctrl-C stops after the running steps) with one stderr line per event,
/// then print_outcome: reproduce's and sweep's common end.
int run_and_print_outcome(const experiments::ReproduceOptions& options,
                          const std::vector<experiments::ReproduceExperiment>& experiments);

}  // namespace meltlab::cli
