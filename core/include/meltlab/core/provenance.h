#pragma once
// Provenance: the one record of where a run's outputs came from, written as the "provenance"
// object of every run folder's record (run.json, compare.json, fit.json, render.json and the
// truth.json of synth-sequence and manufacture):
//   {"subcommand": "simulate",
//    "meltlab": {"version": "...", "git_revision": "..."},
//    "hardware": {"cpu": "...", "threads": 8, "host": "...", ...},
//    "command_line": ["meltlab", "simulate", ...],
//    "started_utc": "2026-11-25T12:04:44Z", "finished_utc": "...",
//    "timings_s": {"total": 12.5, ...},
//    "batch_job": null}        (in a Slurm job: {"scheduler": "slurm", "job_id": "125",
//                               "array_job_id": "120", "array_task_id": "5", "node": "n01",
//                               "cluster": "..."}; the host is hardware.host)
// core knows neither the CLI nor the build: the caller (experiments) fills in the version, the
// git revision, the command line and any hardware facts beyond those core probes.

#include <nlohmann/json.hpp>

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace meltlab {

struct HardwareInfo {
  std::string cpu;                                  ///< the model name from /proc/cpuinfo ("" if unknown)
  unsigned threads = 0;                             ///< std::thread::hardware_concurrency()
  std::string host;                                 ///< gethostname ("" if unknown)
  nlohmann::json extra = nlohmann::json::object();  ///< facts the caller adds (thread pool sizes)
};

/// The machine this process runs on.
HardwareInfo probe_hardware();

/// The batch job this process runs in, from the environment the scheduler sets (Slurm:
/// SLURM_JOB_ID, SLURM_ARRAY_JOB_ID, SLURM_ARRAY_TASK_ID, SLURMD_NODENAME, SLURM_CLUSTER_NAME):
/// the object described above, or null outside a job. Array fields are null for a plain job.
nlohmann::json probe_batch_job();

struct Provenance {
  std::string subcommand;  ///< "simulate", "compare", ...
  std::string version, git_revision;
  HardwareInfo hardware;
  nlohmann::json batch_job;               ///< probe_batch_job() (null outside a batch job)
  std::vector<std::string> command_line;  ///< argv as given
  std::chrono::system_clock::time_point started{}, finished{};
  /// Wall-clock phases in seconds, in the order recorded. "total" (started to finished, on the
  /// steady clock) is added by finish().
  std::vector<std::pair<std::string, double>> timings_s;

  /// Stamps the start (wall clock for the record, steady clock for "total").
  void start();
  /// Stamps the end and records timings_s["total"]; further phases may be added before or after.
  void finish();
  /// The "provenance" object described above.
  nlohmann::json to_json() const;

 private:
  std::chrono::steady_clock::time_point steady_start_{};
};

}  // namespace meltlab
