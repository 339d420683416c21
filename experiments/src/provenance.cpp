#include <meltlab/experiments/provenance.h>
#include <meltlab/version.h>

#include <tbb/info.h>

namespace meltlab::experiments {

Provenance start_provenance(const std::string& subcommand, const std::vector<std::string>& command_line) {
  Provenance p;
  p.subcommand = subcommand;
  p.version = kVersion;
  p.git_revision = kGitRevision;
  p.hardware = probe_hardware();
  // What the parallel loops get by default (cgroup and affinity limits included), which may
  // be fewer than the machine's threads.
  p.hardware.extra["tbb_default_concurrency"] = tbb::info::default_concurrency();
  p.batch_job = probe_batch_job();
  p.command_line = command_line;
  p.start();
  return p;
}

nlohmann::json finish_provenance(Provenance& provenance) {
  provenance.finish();
  return provenance.to_json();
}

}  // namespace meltlab::experiments
