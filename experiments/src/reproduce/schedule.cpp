// meltlab reproduce, stage 3: the schedule. Exclusive experiments (timing measurements) run
// first, one at a time, alone; the others then share the workers. Afterwards: the experiments
// kept from earlier runs (not selected by --only, finished with the current hash), summary.json
// and the HTML report.
#include "stages.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/process.h>
#include <meltlab/core/time.h>
#include <meltlab/version.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <thread>

namespace meltlab::experiments {
namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace reproduce_detail;

namespace {

/// The experiments not selected this time (--only) whose folders are finished with the
/// current hash: they stay in the summary and the report as "kept".
void add_kept(const ReproduceOptions& o, ReproduceResult& result) {
  if (o.only.empty()) return;
  auto all_options = o;
  all_options.only.clear();
  for (const auto& e : load_reproduce_experiments(all_options)) {
    if (std::find(o.only.begin(), o.only.end(), e.name) != o.only.end()) continue;
    std::optional<ExperimentOutcome> kept = read_finished(e);
    if (!kept) continue;
    kept->status = "kept";
    result.experiments.push_back(std::move(*kept));
    result.kept.push_back(e);
  }
}

/// Whether the folder of `e` holds a Slurm submission of this hash that no run has collected
/// or reported (its jobs may still be writing into the folder).
bool submitted_to_slurm(const ReproduceExperiment& e) {
  const fs::path plan = e.out_dir / "slurm" / "plan.json";
  std::error_code ec;
  if (!fs::is_regular_file(plan, ec)) return false;
  try {
    const json p = json::parse(read_text_file(plan, "Slurm plan"));
    return p.value("hash", "") == e.hash && !p.value("reported", false);
  } catch (const std::exception&) {
    return false;
  }
}

json summary_json(const ReproduceOptions& o, const ReproduceResult& result,
                  const std::vector<const ReproduceExperiment*>& listed, int jobs) {
  json ex = json::array();
  for (std::size_t i = 0; i < listed.size(); ++i) {
    const auto& r = result.experiments[i];
    const ReproduceExperiment& x = *listed[i];
    ex.push_back({{"name", r.name},
                  {"title", r.title},
                  {"sources", x.sources},
                  {"status", r.status},
                  {"error", r.error},
                  {"seconds", r.seconds},
                  {"original_seconds", r.original_seconds},
                  {"steps", steps_json(r.steps)},
                  {"hash", x.hash},
                  {"exclusive", x.exclusive},
                  {"config", x.config_file.string()},
                  {"folder", x.name}});
  }
  return json{{"meltlab", {{"version", kVersion}, {"git_revision", kGitRevision}}},
              {"mode", o.quick ? "quick" : "full"},
              {"jobs", jobs},
              {"executor", o.executor},
              {"finished", utc_timestamp_iso8601_now()},
              {"seconds", result.seconds},
              {"interrupted", result.interrupted},
              {"experiments", ex}};
}

/// Runs report/build_report.py over the output folder; returns the report status.
std::string build_report(const ReproduceOptions& o, const Say& say, fs::path& report_file) {
  const fs::path script = o.source_dir / "report" / "build_report.py";
  const fs::path log_out = o.out_dir / "build_report.out", log_err = o.out_dir / "build_report.err";
  say(fmt::format("report: python {} {}", script.string(), o.out_dir.string()));
  int code = -1;
  try {
    ProcessSpec spec;
    spec.argv = {o.python, script.string(), o.out_dir.string()};
    spec.stdin_file = kNullDevice;
    spec.stdout_file = log_out;
    spec.stderr_file = log_err;
    code = run_process(spec).shell_status();
  } catch (const std::exception& ex) {
    return fmt::format("failed: {}", ex.what());
  }
  if (code != 0) return fmt::format("failed: exit {}: {}", code, last_line(log_err));
  report_file = o.out_dir / "report" / "index.html";
  return "built";
}

}  // namespace

ReproduceResult run_reproduce(const ReproduceOptions& o, const std::vector<ReproduceExperiment>& experiments,
                              const std::function<void(const std::string&)>& log, const std::atomic<bool>* stop) {
  using Clock = std::chrono::steady_clock;
  fs::create_directories(o.out_dir);
  const auto t0 = Clock::now();
  std::mutex mu;
  Counters counters;
  std::size_t &finished = counters.finished, &failed = counters.failed, &running = counters.running;
  ReproduceResult result;
  result.experiments.resize(experiments.size());
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  auto say_locked = [&](const std::string& msg) {  // caller holds mu
    log(fmt::format("[{:6.1f}s {}/{} done, {} running, {} failed] {}", elapsed(), finished, experiments.size(), running,
                    failed, msg));
  };
  const Say say = [&](const std::string& msg) {
    std::lock_guard lock(mu);
    say_locked(msg);
  };

  auto run_one = [&](const ReproduceExperiment& e, ExperimentOutcome& out) {
    if (!o.force) {
      if (std::optional<ExperimentOutcome> reused = read_finished(e)) {
        out = std::move(*reused);
        out.status = "reused";
        return;
      }
    }
    if (!o.force && submitted_to_slurm(e)) {
      out.name = e.name;
      out.title = e.title;
      out.hash = e.hash;
      out.status = "failed";
      out.error = fmt::format(
          "its steps were submitted to Slurm ({}) and not collected: run with --executor slurm to collect them, or "
          "--force to run it here (after scancel of its jobs)",
          (e.out_dir / "slurm" / "plan.json").string());
      return;
    }
    run_experiment(o, e, out, say, stop);
  };

  std::vector<std::size_t> alone, shared;
  for (std::size_t i = 0; i < experiments.size(); ++i) (experiments[i].exclusive ? alone : shared).push_back(i);
  std::size_t next = 0;
  const std::vector<std::size_t>* queue = &alone;
  auto worker = [&] {
    for (;;) {
      std::size_t i = 0;
      {
        std::lock_guard lock(mu);
        if (next >= queue->size() || (stop && stop->load())) return;
        i = (*queue)[next++];
        ++running;
      }
      auto& out = result.experiments[i];
      try {
        run_one(experiments[i], out);
      } catch (const std::exception& ex) {
        out.status = "failed";
        out.error = ex.what();
      }
      std::lock_guard lock(mu);
      --running;
      ++finished;
      if (out.status == "failed") ++failed;
      if (out.status == "reused")
        say_locked(fmt::format("{}: reused (finished earlier in {:.1f} s)", out.name, out.original_seconds));
      else if (out.status == "failed")
        say_locked(fmt::format("{}: FAILED after {:.1f} s: {}", out.name, out.seconds, out.error));
      else
        say_locked(fmt::format("{}: done in {:.1f} s", out.name, out.seconds));
    }
  };
  const int jobs = std::max(1, std::min<int>(o.jobs, static_cast<int>(std::max<std::size_t>(1, experiments.size()))));
  if (o.executor == "slurm") {
    run_on_slurm(o, experiments, result.experiments, counters, say, stop);
  } else {
    worker();  // the exclusive ones, on this thread
    next = 0;
    queue = &shared;
    std::vector<std::thread> pool;
    for (int j = 0; j < jobs; ++j) pool.emplace_back(worker);
    for (auto& t : pool) t.join();
  }
  for (std::size_t i = 0; i < experiments.size(); ++i)
    if (result.experiments[i].status.empty()) {
      result.experiments[i].name = experiments[i].name;
      result.experiments[i].title = experiments[i].title;
      result.experiments[i].status = "not run";
      result.experiments[i].error = "interrupted before it started";
    }
  result.interrupted = stop && stop->load();
  result.seconds = elapsed();

  add_kept(o, result);
  std::vector<const ReproduceExperiment*> listed;
  for (const auto& e : experiments) listed.push_back(&e);
  for (const auto& e : result.kept) listed.push_back(&e);
  write_text_atomically(o.out_dir / "summary.json", summary_json(o, result, listed, jobs).dump(2) + "\n");

  result.report_status = "skipped";
  const bool waiting = std::any_of(result.experiments.begin(), result.experiments.end(),
                                   [](const ExperimentOutcome& r) { return r.status == "submitted"; });
  if (waiting) result.report_status = "skipped (experiments still on Slurm: run again to collect them)";
  if (o.report && !result.interrupted && !waiting) result.report_status = build_report(o, say, result.report_file);
  return result;
}

}  // namespace meltlab::experiments
