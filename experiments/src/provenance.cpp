#include <meltlab/experiments/provenance.h>
#include <meltlab/version.h>

#include <meltlab/core/atomic_file.h>

#include <tbb/info.h>

#include <fstream>
#include <string>

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
  // The cache sizes of CPU 0 (Linux sysfs): timings of memory-bound kernels are read against them.
  nlohmann::json caches = nlohmann::json::object();
  for (int i = 0; i < 8; ++i) {
    const std::string dir = "/sys/devices/system/cpu/cpu0/cache/index" + std::to_string(i) + "/";
    std::ifstream level(dir + "level"), type(dir + "type"), size(dir + "size");
    std::string l, t, sz;
    if (!(level >> l) || !(type >> t) || !(size >> sz)) continue;
    caches["L" + l + (t == "Data" ? "d" : t == "Instruction" ? "i" : "")] = sz;
  }
  if (!caches.empty()) p.hardware.extra["caches"] = caches;
  p.batch_job = probe_batch_job();
  p.command_line = command_line;
  p.start();
  return p;
}

nlohmann::json finish_provenance(Provenance& provenance) {
  provenance.finish();
  return provenance.to_json();
}

nlohmann::json commit_run(RunFolder& folder, nlohmann::json record, Provenance& provenance) {
  record["provenance"] = finish_provenance(provenance);
  write_text_atomically(folder.path() / folder.marker(), record.dump(2) + "\n");
  folder.commit();
  return record;
}

}  // namespace meltlab::experiments
