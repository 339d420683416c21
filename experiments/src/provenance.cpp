#include <meltlab/experiments/provenance.h>
#include <meltlab/version.h>

#include <meltlab/core/atomic_file.h>

#include <tbb/info.h>

#include <unistd.h>

#include <fstream>
#include <string>
#include <utility>

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
  // The cache sizes of CPU 0 (Linux sysfs, else CPUID): timings of memory-bound kernels are read
  // against them.
  nlohmann::json caches = nlohmann::json::object();
  for (int i = 0; i < 8; ++i) {
    const std::string dir = "/sys/devices/system/cpu/cpu0/cache/index" + std::to_string(i) + "/";
    std::ifstream level(dir + "level"), type(dir + "type"), size(dir + "size");
    std::string l, t, sz;
    if (!(level >> l) || !(type >> t) || !(size >> sz)) continue;
    caches["L" + l + (t == "Data" ? "d" : t == "Instruction" ? "i" : "")] = sz;
  }
  std::string caches_source = "sysfs";
  if (caches.empty()) {
    // No sysfs cache entries (some VMs): what the CPU reports (glibc's sysconf, from CPUID), in
    // sysfs's notation. Under a VM the L3 is the whole package's, of which a guest may share a part.
    const std::pair<const char*, int> levels[] = {{"L1d", _SC_LEVEL1_DCACHE_SIZE},
                                                  {"L1i", _SC_LEVEL1_ICACHE_SIZE},
                                                  {"L2", _SC_LEVEL2_CACHE_SIZE},
                                                  {"L3", _SC_LEVEL3_CACHE_SIZE}};
    for (const auto& [name, key] : levels)
      if (const long bytes = sysconf(key); bytes > 0) caches[name] = std::to_string(bytes / 1024) + "K";
    caches_source = "cpuid";
  }
  if (!caches.empty()) {
    p.hardware.extra["caches"] = caches;
    p.hardware.extra["caches_source"] = caches_source;
  }
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
