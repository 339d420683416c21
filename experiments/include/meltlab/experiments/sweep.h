#pragma once
// meltlab sweep: one meltlab subcommand run over a grid or a list of option values (any
// simulate/fit/render/... option, --mesh included), as one experiment of the reproduce engine:
// every point is a step (independent of the others: one Slurm job array), then `collect`
// (meltlab sweep --collect: the measures of every point into sweep.csv) and `figures`
// (report/experiment_report.py sweep: one figure per measure, the report fragment). The
// experiment folder is OUT/<name>/; OUT gets summary.json and the HTML report as with reproduce.
//
// Config (YAML, read with core/config.h):
//
//   name: kg_by_mesh                   # [a-z0-9_]+: the folder under --out
//   title: "Melt rate against kg"      # optional
//   command: simulate                  # the meltlab subcommand of every point
//   args: [--cycles, "300", --threads, "1"]   # the same for every point (--out is added)
//   grid:                              # every combination; the first option varies slowest
//     --mesh: [benchmark_a, torus]
//     --kg: [0.5, 0.75, 1.0]
//   points:                            # and/or a list of points (each a map option -> value)
//     - {--mesh: icosphere_3, --kg: 0.6}
//   measures:                          # one CSV column and one figure each
//     - {name: cycles, file: run.json, json: cycles_run}          # a value of a JSON file (a.b.c)
//     - {name: volume, file: stats.csv, column: volume}           # a CSV column's last row
//   x: --kg                            # optional: the figures' x axis (default: the first swept
//                                      # option whose values are all numbers)
//   slurm: {time: "0:30:00", cpus: 1, mem: 1G}   # optional: the points' Slurm resources
//
// An option value `true` is the flag alone, `false` leaves the option out. Points are named
// p000, p001, ... in order (the grid first); every point must set the same options.

#include <meltlab/experiments/reproduce.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace meltlab::experiments {

struct SweepMeasure {
  std::string name;
  std::string file;    ///< relative to the point's folder
  std::string json;    ///< dotted key path into a JSON file, or
  std::string column;  ///< a column of a CSV file (its last row)
};

struct SweepPoint {
  std::string name;                                         ///< p000, p001, ...
  std::vector<std::pair<std::string, std::string>> values;  ///< option -> value, in the options' order
};

struct Sweep {
  std::filesystem::path file;
  std::string text;  ///< the config as read (hashed)
  std::string name, title, command;
  std::vector<std::string> args;
  std::vector<std::string> options;  ///< the swept options, in order
  std::vector<SweepPoint> points;
  std::vector<SweepMeasure> measures;
  std::string x;  ///< the figures' x axis ("" if no option is numeric)
  SlurmResources slurm;
};

/// Reads and checks a sweep config; InputError "FILE:LINE: ..." on bad input.
Sweep load_sweep(const std::filesystem::path& file);

/// The sweep as an experiment of the reproduce engine (steps, hash) under options.out_dir.
ReproduceExperiment sweep_experiment(const Sweep& sweep, const ReproduceOptions& options);

/// Reads every measure of every point folder under `dir` and writes dir/sweep.csv (point, the
/// options, the measures) and dir/sweep.json (what the figures step needs), atomically.
/// InputError naming the point's file and the key when a measure cannot be read.
void collect_sweep(const Sweep& sweep, const std::filesystem::path& dir);

}  // namespace meltlab::experiments
