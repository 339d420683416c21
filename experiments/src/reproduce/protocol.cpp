// meltlab reproduce, stage 2: one experiment into its folder. The steps run in order as child
// processes (stdout/stderr to logs/<step>.out|.err); the folder is complete, and reusable by a
// later run with the same hash, once done.json is written, last and atomically.
#include "stages.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/process.h>
#include <meltlab/core/time.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <mutex>
#include <thread>

namespace meltlab::experiments::reproduce_detail {
namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

std::string quote_join(const std::vector<std::string>& args) {
  std::string s;
  for (const auto& a : args) s += (s.empty() ? "" : " ") + (a.find(' ') == std::string::npos ? a : "'" + a + "'");
  return s;
}

/// Runs one step; returns its outcome. A step that cannot be started sets `error`.
StepOutcome run_step(const ReproduceOptions& o, const ReproduceExperiment& e, const ReproduceStep& s,
                     std::string& error) {
  const ProcessSpec spec = step_process(o, e, s);
  const fs::path err_file = *spec.stderr_file;
  const auto t0 = Clock::now();
  int code = -1;
  try {
    fs::create_directories(spec.stdout_file->parent_path());
    code = run_process(spec).shell_status();
  } catch (const std::exception& ex) {
    error = fmt::format("step {}: {}", s.name, ex.what());
  }
  if (code != 0 && error.empty())
    error = fmt::format("step {} ({} {}) exited with code {}: {}", s.name, s.kind, s.args.empty() ? "" : s.args[0],
                        code, last_line(err_file));
  return {s.name, code, seconds_since(t0)};
}

/// The steps wave by wave (reproduce.h), the steps of one wave on up to o.jobs threads; after a
/// wave with a failed step no further wave starts. out.steps lists the steps that ran, in the
/// config's order; out.error is the first failed step's (in that order).
void run_waves_in_parallel(const ReproduceOptions& o, const ReproduceExperiment& e, ExperimentOutcome& out,
                           const Say& say, const std::atomic<bool>* stop) {
  int last_wave = 0;
  for (const auto& s : e.steps) last_wave = std::max(last_wave, s.wave);
  std::vector<std::optional<StepOutcome>> done(e.steps.size());
  std::vector<std::string> errors(e.steps.size());
  for (int wave = 0; wave <= last_wave && out.status != "failed"; ++wave) {
    std::vector<std::size_t> todo;
    for (std::size_t k = 0; k < e.steps.size(); ++k)
      if (e.steps[k].wave == wave) todo.push_back(k);
    std::mutex mu;
    std::size_t next = 0;
    auto worker = [&] {
      for (;;) {
        std::size_t k = 0;
        {
          std::lock_guard lock(mu);
          if (next >= todo.size() || (stop && stop->load())) return;
          k = todo[next++];
          const auto& s = e.steps[k];
          say(fmt::format("{}: step {}/{} {}: {} {}", e.name, k + 1, e.steps.size(), s.name, s.kind,
                          quote_join(s.args)));
        }
        StepOutcome r = run_step(o, e, e.steps[k], errors[k]);
        std::lock_guard lock(mu);
        done[k] = r;
      }
    };
    std::vector<std::thread> pool;
    for (int j = 0; j < std::min<int>(o.jobs, static_cast<int>(todo.size())); ++j) pool.emplace_back(worker);
    for (auto& t : pool) t.join();
    for (const std::size_t k : todo) {
      if (!done[k]) {
        out.status = "failed";
        if (out.error.empty()) out.error = "interrupted";
      } else if (done[k]->exit_code != 0) {
        out.status = "failed";
        if (out.error.empty()) out.error = errors[k];
      }
    }
  }
  for (const auto& d : done)
    if (d) out.steps.push_back(*d);
}

}  // namespace

ProcessSpec step_process(const ReproduceOptions& o, const ReproduceExperiment& e, const ReproduceStep& s) {
  ProcessSpec spec;
  spec.argv = {s.kind == "meltlab" ? o.self_exe.string() : o.python};
  spec.argv.insert(spec.argv.end(), s.args.begin(), s.args.end());
  spec.search_path = s.kind == "python";  // meltlab is started by its absolute path
  spec.stdin_file = kNullDevice;
  spec.stdout_file = s.stdout_file.empty() ? e.out_dir / "logs" / (s.name + ".out") : s.stdout_file;
  spec.stderr_file = e.out_dir / "logs" / (s.name + ".err");
  return spec;
}

json steps_json(const std::vector<StepOutcome>& steps) {
  json out = json::array();
  for (const auto& s : steps) out.push_back({{"name", s.name}, {"exit_code", s.exit_code}, {"seconds", s.seconds}});
  return out;
}

std::string last_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line)) {
    // the progress line of a tty run is never written to a file, but strip \r just in case
    if (const auto cr = line.rfind('\r'); cr != std::string::npos) line = line.substr(cr + 1);
    if (!line.empty()) last = line;
  }
  return last;
}

std::optional<ExperimentOutcome> read_finished(const ReproduceExperiment& e) {
  const fs::path done = e.out_dir / "done.json";
  std::error_code ec;
  if (!fs::exists(done, ec)) return std::nullopt;
  try {
    const json d = json::parse(read_text_file(done, "experiment"));
    if (d.value("hash", "") != e.hash) return std::nullopt;
    ExperimentOutcome out;
    out.name = e.name;
    out.title = e.title;
    out.hash = e.hash;
    out.original_seconds = d.value("seconds", 0.0);
    for (const auto& s : d.value("steps", json::array()))
      out.steps.push_back({s.value("name", ""), s.value("exit_code", 0), s.value("seconds", 0.0)});
    return out;
  } catch (const std::exception&) {
    return std::nullopt;  // an unreadable marker means the folder is redone
  }
}

void run_experiment(const ReproduceOptions& o, const ReproduceExperiment& e, ExperimentOutcome& out, const Say& say,
                    const std::atomic<bool>* stop) {
  out.name = e.name;
  out.title = e.title;
  out.hash = e.hash;
  const auto t0 = Clock::now();
  std::error_code ec;
  fs::remove_all(e.out_dir, ec);
  fs::create_directories(e.out_dir / "logs");
  out.status = "ran";
  if (o.parallel_steps && o.jobs > 1) {
    run_waves_in_parallel(o, e, out, say, stop);
  } else {
    for (std::size_t k = 0; k < e.steps.size(); ++k) {
      const auto& s = e.steps[k];
      if (stop && stop->load()) {
        out.status = "failed";
        out.error = "interrupted";
        break;
      }
      say(fmt::format("{}: step {}/{} {}: {} {}", e.name, k + 1, e.steps.size(), s.name, s.kind, quote_join(s.args)));
      out.steps.push_back(run_step(o, e, s, out.error));
      if (out.steps.back().exit_code != 0) {
        out.status = "failed";
        break;
      }
    }
  }
  out.seconds = seconds_since(t0);
  if (out.status == "failed") return;
  const json marker = {{"experiment", e.name},
                       {"hash", e.hash},
                       {"mode", o.quick ? "quick" : "full"},
                       {"finished", utc_timestamp_iso8601_now()},
                       {"seconds", out.seconds},
                       {"steps", steps_json(out.steps)},
                       {"config", e.config_file.string()}};
  write_text_atomically(e.out_dir / "done.json", marker.dump(2) + "\n");  // last: the folder is complete
}

}  // namespace meltlab::experiments::reproduce_detail
