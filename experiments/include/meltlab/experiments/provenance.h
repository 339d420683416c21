#pragma once
// The one place that fills the provenance record (core/provenance.h) of a run folder: this
// build's version and git revision (the generated meltlab/version.h), the hardware with the
// thread pool meltlab would use, the command line. Every subcommand with a run folder
// (simulate, compare, fit, render, synth-sequence, manufacture) starts one when its work
// begins and writes `record["provenance"] = finish_provenance(p)` into its record file.

#include <meltlab/core/provenance.h>

#include <string>
#include <vector>

namespace meltlab::experiments {

/// A provenance record of this build for `subcommand`, started now.
Provenance start_provenance(const std::string& subcommand, const std::vector<std::string>& command_line);

/// Stamps the end (and timings_s.total) and returns the "provenance" object.
nlohmann::json finish_provenance(Provenance& provenance);

}  // namespace meltlab::experiments
