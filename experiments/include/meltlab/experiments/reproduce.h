#pragma once
// meltlab reproduce: the main job. Every reproduced table, figure or study of the sources is
// one YAML config (experiments/reproduce/*.yaml) that lists its inputs and its steps; a step
// is a meltlab subcommand (run as a child process of the same binary) or a Python script.
// Steps of one experiment run in order; experiments run in parallel on a bounded number of
// workers. A finished experiment folder holds done.json with the content hash of its config,
// its input files and the meltlab version (written atomically, last); a later run with the
// same hash reuses the folder instead of running it again.
//
// Config format (every string may use ${out}, ${step}, ${repo}, ${config_dir}, ${mode}, ${bin}
// (the folder of the meltlab binary, where the benchmark binaries are built) and the
// config's own vars; a var is a scalar or {quick: ..., full: ...}):
//
//   name: tab_5_1                         # [a-z0-9_]+, unique; the folder under --out
//   title: "Tab. 5.1, Figs. 5.6-5.7: ..."
//   sources: ["Tab. 5.1", "Fig. 5.6"]     # what it reproduces (for the report)
//   inputs: [experiments/configs/x.yaml]  # extra files (relative to the repository) hashed
//   exclusive: true                       # optional: runs alone, before the others (timings)
//   modes: [full]                         # optional (default [quick, full]): the modes it runs in;
//                                         # without --only the others leave it out, --only refuses
//   vars: {cycles: {quick: 3000, full: 20000}}
//   steps:
//     - name: object_b                    # [a-z0-9_]+; ${step} = ${out}/<name>
//       meltlab: [simulate, --mesh, benchmark_b, --cycles, "${cycles}", --out, "${step}"]
//     - name: report
//       python: [report/experiment_report.py, cycle_time, "${out}"]   # script relative to the repository
//       stdout: "${out}/x.json"           # optional: the step's stdout goes to this file
//       slurm: {time: "4:00:00"}          # optional: this step's Slurm resources (below)
//   sweep: experiments/sweeps/x.yaml      # instead of steps: the experiment is that sweep (its
//                                         # points, collect, figures; meltlab/experiments/sweep.h)
//   slurm: {partition: batch, time: "1:00:00", cpus: 2, mem: 4G}   # optional: every step's
//                                         # (--executor slurm; each key optional, defaults below)
//
// Each step's stdout/stderr go to ${out}/logs/<step>.out|.err (unless stdout is redirected).
//
// Dependencies between steps (for the Slurm executor, which runs independent steps at once):
// a step depends on an earlier one when one of its arguments (or its stdout file), read as a
// path, lies in the earlier step's folder ${out}/<name>, is the earlier step's stdout file, or
// is a folder that holds either (${out} itself); a path under ${out} that belongs to no other
// step, and every python step, depend on all earlier steps. A step's "wave" is 0 without
// dependencies, else one more than the latest wave it depends on; the steps of one wave run
// as one Slurm job array, each wave after the one before it (sbatch --dependency=afterok).
// The local executor runs the steps in the file's order.

#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace meltlab::experiments {

/// The Slurm resources of a step (sbatch --partition, --time, --cpus-per-task, --mem). Empty
/// strings and 0: not set at this level (the next level down decides; see SlurmOptions).
struct SlurmResources {
  std::string partition;  ///< empty: the cluster's default partition
  std::string time;       ///< sbatch --time ("60", "1:00:00", "1-12:00:00")
  int cpus = 0;           ///< --cpus-per-task
  std::string mem;        ///< --mem ("4G", "500M")
  /// `over`'s set fields replace these.
  SlurmResources overridden_by(const SlurmResources& over) const;
};

/// The defaults when neither the config nor the command line sets a resource.
inline SlurmResources default_slurm_resources() { return {"", "2:00:00", 2, "4G"}; }

struct ReproduceStep {
  std::string name;
  std::string kind;                     ///< "meltlab" or "python"
  std::vector<std::string> args;        ///< after variable substitution (python: script first, absolute)
  std::filesystem::path stdout_file;    ///< empty: ${out}/logs/<name>.out
  std::vector<std::size_t> depends_on;  ///< indices of the earlier steps it needs (rules above)
  int wave = 0;                         ///< 0 without dependencies, else 1 + the latest wave it needs
  SlurmResources slurm;                 ///< the config's (experiment, then step); unset fields empty
};

struct ReproduceExperiment {
  std::string name;
  std::string title;
  std::vector<std::string> sources;
  std::filesystem::path config_file;
  std::filesystem::path out_dir;
  std::vector<std::filesystem::path> hashed_files;  ///< inputs, scripts and file arguments
  std::vector<ReproduceStep> steps;
  std::string hash;                                 ///< hex content hash (config, mode, hashed files, meltlab version)
  bool exclusive = false;                           ///< run alone (timing measurements), before the others
  std::vector<std::string> modes{"quick", "full"};  ///< the modes it runs in
  bool in_mode = true;                              ///< runs in the mode of this invocation
};

/// How the steps run: child processes of this program (local) or Slurm jobs.
struct SlurmOptions {
  SlurmResources resources;              ///< the command line's: replace the config's
  std::vector<std::string> sbatch_args;  ///< extra sbatch arguments (--account=x, --qos=y)
  bool detach = false;                   ///< submit and return; a later run collects
  double poll_seconds = 10;              ///< squeue/sacct polling interval while waiting
};

struct ReproduceOptions {
  std::vector<std::filesystem::path> config_dirs;  ///< every *.yaml in them is an experiment
  std::filesystem::path out_dir;
  std::filesystem::path source_dir;  ///< the repository (report/ scripts, relative inputs)
  std::filesystem::path self_exe;    ///< the meltlab binary run for the meltlab steps
  std::string python = "/usr/bin/python3";
  bool quick = false;
  std::vector<std::string> only;  ///< empty: all
  int jobs = 2;
  bool force = false;              ///< run even if a finished folder with the same hash exists
  bool report = true;              ///< run report/build_report.py at the end
  std::string executor = "local";  ///< "local" or "slurm"
  SlurmOptions slurm;
  bool parallel_steps = false;  ///< local: the steps of one wave share the --jobs workers (sweeps)
};

/// Loads and validates the configs of `options.config_dirs` (and `only`), substitutes the
/// variables and computes the hashes. Throws InputError naming the config file on bad input.
std::vector<ReproduceExperiment> load_reproduce_experiments(const ReproduceOptions& options);

struct StepOutcome {
  std::string name;
  int exit_code = 0;
  double seconds = 0;
};

struct ExperimentOutcome {
  std::string name;
  std::string title;
  /// "ran", "reused", "failed", "not run" (interrupted), "kept" (not selected, finished
  /// earlier), "submitted" (Slurm, --detach or interrupted while waiting: a later run collects)
  std::string status;
  std::string error;
  double seconds = 0;           ///< this invocation
  double original_seconds = 0;  ///< reused: the run that made the folder
  std::vector<StepOutcome> steps;
  std::string hash;
};

struct ReproduceResult {
  std::vector<ExperimentOutcome> experiments;  ///< the selected ones in order, then the kept ones
  std::vector<ReproduceExperiment> kept;       ///< not selected (--only) but finished with the current hash
  double seconds = 0;
  std::string report_status;  ///< "built", "failed: ...", "skipped"
  std::filesystem::path report_file;
  bool interrupted = false;
};

/// Runs the experiments (reusing finished ones), writes <out>/summary.json and, if asked,
/// builds the report. `log` receives one progress line per event (thread-safe calls).
/// With options.executor "slurm" the steps are submitted as Slurm jobs (see slurm.h) and
/// waited for, or with slurm.detach left running; a later run collects them.
ReproduceResult run_reproduce(const ReproduceOptions& options, const std::vector<ReproduceExperiment>& experiments,
                              const std::function<void(const std::string&)>& log, const std::atomic<bool>* stop);

/// `meltlab run-job`: runs the step of job `job_index` of a Slurm plan (slurm/plan.json of an
/// experiment folder; in an array job the task SLURM_ARRAY_TASK_ID), then writes its record
/// slurm/steps/<step>.json atomically (exit code, times, provenance with the host, job id and
/// array index). Returns the step's exit status (0 or 1..255).
int run_slurm_job(const std::filesystem::path& plan, std::size_t job_index,
                  const std::vector<std::string>& command_line);

}  // namespace meltlab::experiments
