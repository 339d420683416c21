// meltlab sweep: one subcommand over a grid or list of option values, locally or as a Slurm
// job array, on the reproduce engine (meltlab/experiments/sweep.h); one CSV and one figure per
// measure, in the HTML report.

#include <meltlab/core/error.h>
#include <meltlab/experiments/reproduce.h>
#include <meltlab/experiments/sweep.h>

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>

#include "commands.h"

#ifndef MELTLAB_SOURCE_DIR
#error "MELTLAB_SOURCE_DIR must name the repository (set by experiments/CMakeLists.txt)"
#endif

namespace meltlab::cli {
Run add_sweep(CLI::App& app, const std::vector<std::string>&) {
  namespace fs = std::filesystem;
  auto* sub = app.add_subcommand(
      "sweep",
      "Run one subcommand over a grid or list of option values (locally or as a Slurm job array): one CSV "
      "and one figure per measure, in the report");
  auto o = std::make_shared<experiments::ReproduceOptions>();
  auto config = std::make_shared<std::string>();
  auto collect = std::make_shared<std::string>();
  auto source_dir = std::make_shared<std::string>(MELTLAB_SOURCE_DIR);
  auto list = std::make_shared<bool>(false);
  auto no_report = std::make_shared<bool>(false);
  sub->add_option("--config", *config, "The sweep (YAML; format in experiments/include/meltlab/experiments/sweep.h)")
      ->required();
  auto* out = sub->add_option("--out", o->out_dir,
                              "Output folder: OUT/<name>/ (a folder per point, sweep.csv, figures), summary.json, "
                              "report/index.html");
  sub->add_option("--collect", *collect,
                  "Only write sweep.csv from the finished points in this folder (the sweep's own collect step)")
      ->excludes(out);
  sub->add_option("--jobs", o->jobs, "Points run in parallel (local executor)")
      ->default_val(2)
      ->check(CLI::Range(1, 64));
  sub->add_option("--source-dir", *source_dir, "The meltlab repository (report/ scripts)")
      ->default_str(MELTLAB_SOURCE_DIR);
  sub->add_option("--python", o->python, "Python interpreter with matplotlib")->default_val("/usr/bin/python3");
  sub->add_flag("--force", o->force, "Run again even if a finished sweep with the same hash exists");
  sub->add_flag("--no-report", *no_report, "Do not build the HTML report");
  sub->add_flag("--list", *list, "List the points (name and arguments) and exit");
  add_executor_options(*sub, *o);
  return [=]() -> int {
    const experiments::Sweep sweep = experiments::load_sweep(fs::absolute(*config));
    if (!collect->empty()) {
      experiments::collect_sweep(sweep, fs::absolute(*collect));
      std::printf("%s\n", (fs::absolute(*collect) / "sweep.csv").string().c_str());
      return kExitOk;
    }
    if (o->out_dir.empty()) throw InputError("sweep: --out is required (or --collect)");
    o->source_dir = fs::absolute(*source_dir);
    o->out_dir = fs::absolute(o->out_dir);
    o->report = !*no_report;
    o->parallel_steps = true;
    if (!fs::is_regular_file(o->source_dir / "report" / "build_report.py"))
      throw InputError(fmt::format("--source-dir: '{}' has no report/build_report.py", o->source_dir.string()));
    o->self_exe = fs::read_symlink("/proc/self/exe");
    const std::vector<experiments::ReproduceExperiment> experiments{experiments::sweep_experiment(sweep, *o)};
    if (*list) {
      for (const auto& s : experiments.front().steps) {
        std::string args;
        for (const auto& a : s.args) args += " " + a;
        std::printf("%-10s %s%s\n", s.name.c_str(), s.kind.c_str(), args.c_str());
      }
      if (o->executor == "slurm") print_waves(experiments.front(), o->slurm);
      return kExitOk;
    }
    std::fprintf(stderr, "meltlab sweep: %s, %zu point(s) of %s over %zu option(s), %s, output %s\n",
                 sweep.name.c_str(), sweep.points.size(), sweep.command.c_str(), sweep.options.size(),
                 o->executor == "slurm" ? (o->slurm.detach ? "on Slurm (detached)" : "on Slurm")
                                        : fmt::format("{} job(s)", o->jobs).c_str(),
                 o->out_dir.string().c_str());
    return run_and_print_outcome(*o, experiments);
  };
}

}  // namespace meltlab::cli
