#pragma once
// The frame of the bench subcommands made of named studies (`meltlab volume bench`, `meltlab fog
// bench`): the study names and repeat counts checked before anything is written, one run folder
// (bench.json), each study timed with the machine's load average beside it (the cores are
// shared), and one record committed atomically at the end.
//
// bench.json: {mode, warmup, repeats, studies, load_average_start: [1, 5, 15 min],
//              study_seconds: {study: s}, load_average_after: {study: [...]},
//              load_average_end: [...], <whatever the studies add>, provenance}

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct BenchStudiesRun {
  std::string command;  ///< "volume bench", for the provenance record and messages
  std::vector<std::string> studies;
  bool quick = true;
  int warmup = 1, repeats = 3;
  std::filesystem::path out_dir;
  bool overwrite = false;
  std::vector<std::string> command_line;
};

/// One study: writes its files into `dir` and its summary into `record`.
using BenchStudy = std::function<void(const std::filesystem::path& dir, nlohmann::json& record)>;

/// Runs run.studies (in order) from `known`. Throws InputError, before the run folder exists, for
/// an unknown study (naming the known ones), repeats < 1 or warmup < 0.
void run_bench_studies(const BenchStudiesRun& run, const std::map<std::string, BenchStudy>& known);

}  // namespace meltlab::experiments
