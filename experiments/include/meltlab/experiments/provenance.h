#pragma once
// The one place that fills the provenance record (core/provenance.h) of a run folder: this
// build's version and git revision (the generated meltlab/version.h), the hardware with the
// thread pool meltlab would use, the command line. Every subcommand with a run folder
// (simulate, compare, fit, render, volume, predict, ...) starts one when its work begins and ends
// with commit_run(folder, record, p), which stamps it into the record file and commits the folder.

#include <meltlab/core/provenance.h>
#include <meltlab/core/run_folder.h>

#include <string>
#include <vector>

namespace meltlab::experiments {

/// A provenance record of this build for `subcommand`, started now.
Provenance start_provenance(const std::string& subcommand, const std::vector<std::string>& command_line);

/// Stamps the end (and timings_s.total) and returns the "provenance" object.
nlohmann::json finish_provenance(Provenance& provenance);

/// The end of every run: the provenance stamped into `record`, the record written (atomically) as
/// the folder's marker file (render.json, fit.json, ...), the folder committed. Returns the record.
nlohmann::json commit_run(RunFolder& folder, nlohmann::json record, Provenance& provenance);

}  // namespace meltlab::experiments
