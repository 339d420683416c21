#pragma once
// The Slurm client of meltlab: sbatch, squeue, sacct, scontrol and scancel run as child
// processes (core/process.h) from PATH, their output read from a file. Used by the Slurm
// executor of `meltlab reproduce` and `meltlab sweep` (docs/cluster.md); meltlab runs no
// scheduler of its own, it submits job chains and arrays and asks Slurm how they are doing.

#include <meltlab/experiments/reproduce.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace meltlab::experiments::slurm {

/// One sbatch submission: a batch script, as a plain job or as an array of `array_size` tasks.
struct JobRequest {
  std::filesystem::path script;         ///< the batch script (its #! line names the shell)
  std::string name;                     ///< --job-name
  SlurmResources resources;             ///< every field set (partition may be empty: the default)
  int array_size = 0;                   ///< > 0: --array=0-(array_size-1)
  std::vector<std::string> after_ok;    ///< job ids it waits for (--dependency=afterok:..., killed if one fails)
  std::filesystem::path log;            ///< --output and --error (%a: the array index)
  std::filesystem::path workdir;        ///< --chdir
  bool exclusive = false;               ///< --exclusive (timing measurements: a node alone)
  std::vector<std::string> extra_args;  ///< more sbatch options, as given
};

/// The sbatch command line of `r` (without the program name).
std::vector<std::string> sbatch_arguments(const JobRequest& r);

/// Submits `r`; returns the job id. `scratch` is a file for sbatch's output. Throws InputError
/// with sbatch's message if it refuses (no such partition, a time over the limit, no Slurm).
std::string submit(const JobRequest& r, const std::filesystem::path& scratch);

/// Cancels jobs (scancel); errors ignored (a job that has ended already).
void cancel(const std::vector<std::string>& job_ids, const std::filesystem::path& scratch);

/// What Slurm says of one task ("123" for a plain job, "123_4" for task 4 of array 123).
struct TaskState {
  std::string state;      ///< PENDING, RUNNING, COMPLETED, FAILED, CANCELLED, TIMEOUT, OUT_OF_MEMORY, ...
  std::string reason;     ///< squeue/scontrol Reason (Dependency, DependencyNeverSatisfied, ...)
  std::string exit_code;  ///< "exit:signal" once finished
  bool live = false;      ///< still in the queue (pending, running, completing, suspended)
};

/// The tasks of `job_ids` that Slurm knows: the queued ones from squeue (this user's jobs);
/// those no longer queued from sacct, or where accounting is off from scontrol (which keeps
/// finished jobs for MinJobAge). Tasks Slurm has forgotten are absent. Throws InputError if
/// squeue itself fails (the controller unreachable).
std::map<std::string, TaskState> query(const std::vector<std::string>& job_ids, const std::filesystem::path& scratch);

/// Parses `squeue -h -r -o %i|%T|%r` lines.
std::map<std::string, TaskState> parse_squeue(const std::string& text);
/// Parses `sacct -n -P -X -o JobID,State,ExitCode` lines ("CANCELLED by 0" is CANCELLED).
std::map<std::string, TaskState> parse_sacct(const std::string& text);
/// Parses `scontrol show job -o` lines (one per job or array task).
std::map<std::string, TaskState> parse_scontrol(const std::string& text);

/// The job id a task id belongs to ("123_4" and "123" -> "123").
std::string job_of_task(const std::string& task_id);

/// `s` quoted for a POSIX shell (single quotes).
std::string shell_quote(const std::string& s);

}  // namespace meltlab::experiments::slurm
