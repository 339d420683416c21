// meltlab reproduce: run the experiment configs (one per reproduced table/figure/study),
// reusing finished ones, and build the HTML report.

#include <meltlab/experiments/reproduce.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <unistd.h>

#include "cli_util.h"
#include "commands.h"

#ifndef MELTLAB_SOURCE_DIR
#error "MELTLAB_SOURCE_DIR must name the repository (set by experiments/CMakeLists.txt)"
#endif

namespace meltlab::cli {
void add_executor_options(CLI::App& sub, experiments::ReproduceOptions& o) {
  auto& s = o.slurm;
  sub.add_option("--executor", o.executor,
                 "Where the steps run: local (child processes of this program) or slurm (sbatch jobs; docs/cluster.md)")
      ->check(CLI::IsMember({"local", "slurm"}))
      ->default_val("local");
  sub.add_option("--partition", s.resources.partition, "Slurm: partition of every job (replaces the configs')")
      ->check([](const std::string& v) {
        return v.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.,-") ==
                       std::string::npos
                   ? std::string()
                   : "not a partition name";
      });
  sub.add_option("--time", s.resources.time, "Slurm: time limit of every job (minutes, H:MM:SS, D-HH:MM:SS)")
      ->check([](const std::string& v) {
        return !v.empty() && v.find_first_not_of("0123456789:-") == std::string::npos ? std::string()
                                                                                      : "not a Slurm time limit";
      });
  sub.add_option("--cpus", s.resources.cpus, "Slurm: CPUs of every job (--cpus-per-task)")->check(CLI::Range(1, 4096));
  sub.add_option("--mem", s.resources.mem, "Slurm: memory of every job (4G, 500M)")->check([](const std::string& v) {
    const auto digits = v.find_first_not_of("0123456789");
    return digits > 0 && (digits == std::string::npos ||
                          (digits + 1 == v.size() && std::string("KMGT").find(v.back()) != std::string::npos))
               ? std::string()
               : "not a Slurm memory size";
  });
  sub.add_option("--sbatch-arg", s.sbatch_args,
                 "Slurm: one more sbatch option for every job (repeatable: --account=x)");
  sub.add_flag("--detach", s.detach, "Slurm: submit and return; run the same command again to collect");
  sub.add_option("--poll-seconds", s.poll_seconds, "Slurm: how often squeue is asked while waiting")
      ->default_val(10)
      ->check(CLI::Range(0.1, 3600.0));
}

void print_waves(const experiments::ReproduceExperiment& e, const experiments::SlurmOptions& s) {
  int last = 0;
  for (const auto& step : e.steps) last = std::max(last, step.wave);
  for (int w = 0; w <= last; ++w) {
    std::string names;
    for (const auto& step : e.steps)
      if (step.wave == w) {
        const auto r = experiments::default_slurm_resources().overridden_by(step.slurm).overridden_by(s.resources);
        names += fmt::format("{}{} [{}{} cpus, {}, {}]", names.empty() ? "" : ", ", step.name,
                             r.partition.empty() ? "" : r.partition + ", ", r.cpus, r.mem, r.time);
      }
    std::printf("    wave %d: %s\n", w, names.c_str());
  }
}

Run add_reproduce(CLI::App& app) {
  namespace fs = std::filesystem;
  auto* sub = app.add_subcommand("reproduce",
                                 "Run the reproduction experiments (one YAML config per table/figure/study), reuse "
                                 "finished ones, build the report");
  auto o = std::make_shared<experiments::ReproduceOptions>();
  auto configs = std::make_shared<std::vector<std::string>>();
  auto source_dir = std::make_shared<std::string>(MELTLAB_SOURCE_DIR);
  auto list = std::make_shared<bool>(false);
  auto no_report = std::make_shared<bool>(false);
  sub->add_option("--out", o->out_dir, "Output folder: one subfolder per experiment, summary.json, report/index.html")
      ->required();
  sub->add_flag("--quick", o->quick,
                "Reduced sizes (the default of ./scripts/reproduce; < 10 min on 2 cores); experiments with modes: "
                "[full] are left out");
  sub->add_option("--only", o->only, "Run only these experiments (repeatable)")->delimiter(',');
  sub->add_option("--jobs", o->jobs, "Experiments run in parallel")->default_val(2)->check(CLI::Range(1, 64));
  sub->add_option("--configs", *configs,
                  "Folders of experiment configs (repeatable; default <source>/experiments/reproduce)");
  sub->add_option("--source-dir", *source_dir, "The meltlab repository (report/ scripts, relative inputs)")
      ->default_str(MELTLAB_SOURCE_DIR);
  sub->add_option("--python", o->python, "Python interpreter with matplotlib")->default_val("/usr/bin/python3");
  sub->add_flag("--force", o->force, "Run every experiment even if a finished folder with the same hash exists");
  sub->add_flag("--no-report", *no_report, "Do not build the HTML report");
  sub->add_flag("--list", *list, "List the experiments (name, steps, hash) and exit");
  add_executor_options(*sub, *o);
  return [=]() -> int {
    o->source_dir = fs::absolute(*source_dir);
    o->out_dir = fs::absolute(o->out_dir);
    o->report = !*no_report;
    o->config_dirs.clear();
    if (configs->empty()) o->config_dirs.push_back(o->source_dir / "experiments" / "reproduce");
    for (const auto& c : *configs) o->config_dirs.push_back(fs::absolute(c));
    if (!fs::is_regular_file(o->source_dir / "report" / "build_report.py"))
      throw InputError(fmt::format("--source-dir: '{}' has no report/build_report.py", o->source_dir.string()));
    o->self_exe = fs::read_symlink("/proc/self/exe");
    const auto experiments = experiments::load_reproduce_experiments(*o);
    if (experiments.empty()) throw InputError("reproduce: no experiment configs found");
    if (*list) {
      for (const auto& e : experiments) {
        std::printf("%-22s %zu steps  %s  %s\n", e.name.c_str(), e.steps.size(), e.hash.c_str(), e.title.c_str());
        if (o->executor == "slurm") print_waves(e, o->slurm);
      }
      return kExitOk;
    }
    if (o->executor == "slurm")
      std::fprintf(stderr, "meltlab reproduce: %zu experiment(s), %s mode, on Slurm%s, output %s\n", experiments.size(),
                   o->quick ? "quick" : "full", o->slurm.detach ? " (detached)" : "", o->out_dir.string().c_str());
    else
      std::fprintf(stderr, "meltlab reproduce: %zu experiment(s), %s mode, %d job(s), output %s\n", experiments.size(),
                   o->quick ? "quick" : "full", o->jobs, o->out_dir.string().c_str());
    return run_and_print_outcome(*o, experiments);
  };
}

int run_and_print_outcome(const experiments::ReproduceOptions& o,
                          const std::vector<experiments::ReproduceExperiment>& experiments) {
  InterruptScope interrupt;
  const auto result = experiments::run_reproduce(
      o, experiments,
      [](const std::string& line) {
        std::fprintf(stderr, "%s\n", line.c_str());
        std::fflush(stderr);
      },
      interrupt.flag());
  return print_outcome(result, o.out_dir);
}

int print_outcome(const experiments::ReproduceResult& result, const std::filesystem::path& out_dir) {
  int ran = 0, reused = 0, failed = 0, kept = 0, submitted = 0;
  std::printf("\n%-22s %-8s %9s  %s\n", "experiment", "status", "seconds", "error / steps");
  for (const auto& r : result.experiments) {
    ran += r.status == "ran";
    reused += r.status == "reused";
    kept += r.status == "kept";
    failed += r.status == "failed" || r.status == "not run";
    submitted += r.status == "submitted";
    std::string detail = r.error;
    if (detail.empty())
      for (const auto& s : r.steps)
        detail += fmt::format("{}{} {:.1f}s", detail.empty() ? "" : ", ", s.name, s.seconds);
    const bool earlier = r.status == "reused" || r.status == "kept";
    std::printf("%-22s %-8s %9.1f  %s%s\n", r.name.c_str(), r.status.c_str(), earlier ? r.original_seconds : r.seconds,
                detail.c_str(), earlier ? " (earlier run)" : "");
  }
  std::printf("%d ran, %d reused, %d failed in %.1f s; %d more kept from earlier runs; summary: %s\n", ran, reused,
              failed, result.seconds, kept, (out_dir / "summary.json").string().c_str());
  if (submitted > 0)
    std::printf("%d still on Slurm: run the same command again (without --detach) to collect them\n", submitted);
  std::printf("report: %s\n",
              result.report_status == "built" ? result.report_file.string().c_str() : result.report_status.c_str());
  if (result.interrupted) return kExitInterrupted;
  return failed > 0 || result.report_status.rfind("failed", 0) == 0 ? kExitInvalid : kExitOk;
}

}  // namespace meltlab::cli
