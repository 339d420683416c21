#include <meltlab/core/provenance.h>
#include <meltlab/core/time.h>

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <thread>

namespace meltlab {

HardwareInfo probe_hardware() {
  HardwareInfo h;
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line))
    if (line.rfind("model name", 0) == 0) {
      // "model name\t: Intel(R) ...": the value after the colon, without its leading blanks.
      const auto value = line.find_first_not_of(" \t", line.find(':') + 1);
      if (line.find(':') != std::string::npos && value != std::string::npos) h.cpu = line.substr(value);
      break;
    }
  h.threads = std::thread::hardware_concurrency();
  char host[256] = {0};
  if (::gethostname(host, sizeof host - 1) == 0) h.host = host;
  return h;
}

nlohmann::json probe_batch_job() {
  const auto env = [](const char* name) -> nlohmann::json {
    const char* v = std::getenv(name);
    return v && *v ? nlohmann::json(v) : nlohmann::json();
  };
  const nlohmann::json job_id = env("SLURM_JOB_ID");
  if (job_id.is_null()) return nullptr;
  return {{"scheduler", "slurm"},
          {"job_id", job_id},
          {"array_job_id", env("SLURM_ARRAY_JOB_ID")},
          {"array_task_id", env("SLURM_ARRAY_TASK_ID")},
          {"node", env("SLURMD_NODENAME")},
          {"cluster", env("SLURM_CLUSTER_NAME")}};
}

void Provenance::start() {
  started = std::chrono::system_clock::now();
  steady_start_ = std::chrono::steady_clock::now();
}

void Provenance::finish() {
  finished = std::chrono::system_clock::now();
  timings_s.emplace_back("total",
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - steady_start_).count());
}

nlohmann::json Provenance::to_json() const {
  nlohmann::json hw = {{"cpu", hardware.cpu}, {"threads", hardware.threads}, {"host", hardware.host}};
  for (const auto& [k, v] : hardware.extra.items()) hw[k] = v;
  nlohmann::json timings = nlohmann::json::object();
  for (const auto& [name, seconds] : timings_s) timings[name] = seconds;
  return {{"subcommand", subcommand},
          {"meltlab", {{"version", version}, {"git_revision", git_revision}}},
          {"hardware", hw},
          {"command_line", command_line},
          {"started_utc", utc_timestamp_iso8601(started)},
          {"finished_utc", utc_timestamp_iso8601(finished)},
          {"timings_s", timings},
          {"batch_job", batch_job}};
}

}  // namespace meltlab
