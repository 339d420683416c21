#include <meltlab/experiments/bench_studies.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/core/error.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/core/time.h>

#include <fmt/format.h>

namespace meltlab::experiments {

void run_bench_studies(const BenchStudiesRun& o, const std::map<std::string, BenchStudy>& known) {
  for (const auto& s : o.studies)
    if (!known.count(s)) {
      std::string names;
      for (const auto& [k, v] : known) names += (names.empty() ? "" : ", ") + k;
      throw InputError(fmt::format("--study: unknown study '{}' ({})", s, names));
    }
  if (o.repeats < 1 || o.warmup < 0) throw InputError("--repeats must be >= 1 and --warmup >= 0");
  RunFolder folder(o.out_dir, RunFolderOptions{"--out", "bench.json", o.command, o.overwrite});
  Provenance provenance = start_provenance(o.command, o.command_line);
  nlohmann::json record;
  record["mode"] = o.quick ? "quick" : "full";
  record["warmup"] = o.warmup;
  record["repeats"] = o.repeats;
  record["studies"] = o.studies;
  record["load_average_start"] = load_averages();
  for (const auto& s : o.studies) {
    const auto t0 = std::chrono::steady_clock::now();
    known.at(s)(folder.path(), record);
    record["study_seconds"][s] = ms_since(t0) / 1000;
    record["load_average_after"][s] = load_averages();
  }
  record["load_average_end"] = load_averages();
  commit_run(folder, std::move(record), provenance);
}

}  // namespace meltlab::experiments
