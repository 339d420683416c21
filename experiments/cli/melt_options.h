#pragma once
// The melt options of the subcommands that run the empirical model (simulate, synth-sequence,
// fit, render): --kg --ke --kn --kr --units --kl --precision --threads, declared in one place.
// Each subcommand keeps the options and defaults it has always had (MeltOptionSet).

#include <meltlab/experiments/simulate_run.h>

#include <CLI/CLI.hpp>

#include <functional>
#include <string>

namespace meltlab::cli {

/// Which melt options a subcommand offers, and their defaults (the subcommands differ: fit
/// starts kg at 0.5 and has no --kn; render has neither --kn, --units, --kl nor --precision).
struct MeltOptionSet {
  double kg = 1.0;
  double kE = 0.05;
  double kr = 0.5;
  std::string kg_help = "Global rate coefficient kg in [0, 1] (ambient temperature)";
  std::string kl_help = "YAML file with the local coefficient field (top-level key 'kl'); default kl = 1";
  bool kn = true;         ///< --kn (default kE / 100)
  bool units = true;      ///< --units relative|absolute; without it, coefficients are relative to L0
  bool kl = true;         ///< --kl FILE
  bool precision = true;  ///< --precision float|double; without it, double
  bool threads = false;   ///< --threads N (default 0 = all cores)
};

/// Declares the melt options of `set` on `sub`, bound to `options` (which must outlive the
/// parse). Returns the step that stores the parsed choices (--kn, --units, --precision) in
/// `options`: call it first in the subcommand's run function.
std::function<void()> add_melt_options(CLI::App& sub, experiments::SimulateOptions& options, const MeltOptionSet& set);

}  // namespace meltlab::cli
