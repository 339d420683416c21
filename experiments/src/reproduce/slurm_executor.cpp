// meltlab reproduce, the Slurm executor: the same experiments, folders, hashes and done.json as
// the local run, with each step run as a Slurm job by `meltlab run-job` (docs/cluster.md).
//
// Per experiment folder OUT/<name>/slurm/:
//   plan.json            what was submitted: the steps (program, arguments, log files), the jobs
//                        (id, wave, the steps of each task), the experiment's hash; written
//                        before the first sbatch and again with the job ids
//   job-<k>.sh           the batch script of job k: `meltlab run-job --plan plan.json --job k`
//   logs/job-<k>[_<a>].log  Slurm's output of job k (array task a)
//   steps/<step>.json    written by the job, atomically, when its step has exited: exit code,
//                        times, provenance (host, job id, array index)
// A step is done when its record says exit 0 for this hash. The experiment is done when every
// step is: then this process writes done.json, last, as the local run does. A failed or
// cancelled job is reported once (plan.json "reported"); the next run resubmits the steps
// without a successful record (a resume), in their waves.
#include "stages.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/time.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/experiments/slurm.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <set>
#include <thread>

namespace meltlab::experiments {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

double unix_now() { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); }

fs::path slurm_dir(const ReproduceExperiment& e) { return e.out_dir / "slurm"; }
fs::path plan_file(const ReproduceExperiment& e) { return slurm_dir(e) / "plan.json"; }
fs::path record_file(const fs::path& slurm, const std::string& step) { return slurm / "steps" / (step + ".json"); }

std::optional<json> read_json(const fs::path& p) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) return std::nullopt;
  try {
    return json::parse(read_text_file(p, "Slurm record"));
  } catch (const std::exception&) {
    return std::nullopt;  // unreadable (half-written records never exist: written atomically)
  }
}

/// The record of `step` if it is this hash's and says exit 0.
std::optional<json> success_record(const ReproduceExperiment& e, const std::string& step) {
  auto r = read_json(record_file(slurm_dir(e), step));
  if (!r || r->value("hash", "") != e.hash || r->value("exit_code", -1) != 0) return std::nullopt;
  return r;
}

}  // namespace

namespace reproduce_detail {
namespace {

struct Job {
  std::string id;
  int wave = 0;
  std::vector<std::size_t> steps;  ///< step indices; task a of an array runs steps[a]
  bool array = false;
  std::string task_id(std::size_t a) const { return array ? fmt::format("{}_{}", id, a) : id; }
  fs::path log(const fs::path& slurm, std::size_t a) const {
    return slurm / "logs" /
           (array ? fmt::format("job-{}_{}.log", wave_index, a) : fmt::format("job-{}.log", wave_index));
  }
  std::size_t wave_index = 0;  ///< k of job-<k>
};

/// One experiment on the cluster.
struct Tracked {
  const ReproduceExperiment* e = nullptr;
  ExperimentOutcome* out = nullptr;
  std::vector<Job> jobs;
  std::map<std::size_t, std::string> shown;  ///< step -> the last state shown in progress
  bool terminal = false;
  int missing_records = 0;  ///< polls on which a COMPLETED job's record was not there yet
};

json plan_json(const ReproduceOptions& o, const ReproduceExperiment& e, const std::vector<Job>& jobs) {
  json steps = json::array();
  for (std::size_t k = 0; k < e.steps.size(); ++k) {
    const ProcessSpec spec = step_process(o, e, e.steps[k]);
    steps.push_back({{"name", e.steps[k].name},
                     {"argv", spec.argv},
                     {"search_path", spec.search_path},
                     {"stdout", spec.stdout_file->string()},
                     {"stderr", spec.stderr_file->string()},
                     // what a job removes before its step runs: a job that Slurm requeues (a node
                     // failed) starts on a clean slate, as a local step does in a fresh folder
                     {"clear", {(e.out_dir / e.steps[k].name).string(), spec.stdout_file->string()}}});
  }
  json js = json::array();
  for (const auto& j : jobs) {
    json names = json::array();
    for (const auto k : j.steps) names.push_back(e.steps[k].name);
    js.push_back({{"id", j.id}, {"wave", j.wave}, {"array", j.array}, {"steps", names}});
  }
  return {{"experiment", e.name},
          {"hash", e.hash},
          {"mode", o.quick ? "quick" : "full"},
          {"steps", steps},
          {"jobs", js},
          {"submitted_utc", utc_timestamp_iso8601_now()},
          {"reported", false},
          {"meltlab", o.self_exe.string()}};
}

/// The jobs of a plan read back (ids, waves, step indices by name).
std::vector<Job> plan_jobs(const json& plan, const ReproduceExperiment& e) {
  std::vector<Job> jobs;
  for (const auto& j : plan.at("jobs")) {
    Job job;
    job.id = j.at("id").get<std::string>();
    job.wave = j.at("wave").get<int>();
    job.array = j.at("array").get<bool>();
    job.wave_index = jobs.size();
    for (const auto& n : j.at("steps")) {
      const auto it = std::find_if(e.steps.begin(), e.steps.end(), [&](const auto& s) { return s.name == n; });
      if (it == e.steps.end()) throw InputError("plan names an unknown step");
      job.steps.push_back(static_cast<std::size_t>(it - e.steps.begin()));
    }
    jobs.push_back(std::move(job));
  }
  return jobs;
}

/// Removes what a step leaves behind (its folder, its stdout file, its logs and record), so a
/// resumed step starts as on a fresh folder.
void clear_step(const ReproduceOptions& o, const ReproduceExperiment& e, const ReproduceStep& s) {
  std::error_code ec;
  const ProcessSpec spec = step_process(o, e, s);
  fs::remove_all(e.out_dir / s.name, ec);
  fs::remove(*spec.stdout_file, ec);
  fs::remove(*spec.stderr_file, ec);
  fs::remove(record_file(slurm_dir(e), s.name), ec);
}

/// Submits the steps of `e` without a successful record (all of them on a fresh folder) as one
/// job (array) per wave and resource set, each wave after the one before.
std::vector<Job> submit_experiment(const ReproduceOptions& o, const ReproduceExperiment& e, bool resume,
                                   const Say& say) {
  std::error_code ec;
  std::vector<std::size_t> todo;
  if (!resume) {
    fs::remove_all(e.out_dir, ec);
    for (std::size_t k = 0; k < e.steps.size(); ++k) todo.push_back(k);
  } else {
    for (std::size_t k = 0; k < e.steps.size(); ++k)
      if (!success_record(e, e.steps[k].name)) todo.push_back(k);
    for (const auto k : todo) clear_step(o, e, e.steps[k]);
    fs::remove(e.out_dir / "done.json", ec);
  }
  const fs::path slurm = slurm_dir(e);
  fs::create_directories(e.out_dir / "logs");
  fs::create_directories(slurm / "logs");
  fs::create_directories(slurm / "steps");

  // Jobs: by wave, then by resources (one array needs one resource set).
  std::map<int, std::map<std::tuple<std::string, std::string, int, std::string>, std::vector<std::size_t>>> groups;
  for (const auto k : todo) {
    const SlurmResources r = default_slurm_resources().overridden_by(e.steps[k].slurm).overridden_by(o.slurm.resources);
    groups[e.steps[k].wave][{r.partition, r.time, r.cpus, r.mem}].push_back(k);
  }
  std::vector<Job> jobs;
  std::vector<slurm::JobRequest> requests;
  if (todo.empty()) return jobs;
  for (const auto& [wave, by_resources] : groups)
    for (const auto& [res, steps] : by_resources) {
      Job j;
      j.wave = wave;
      j.steps = steps;
      j.array = steps.size() > 1;
      j.wave_index = jobs.size();
      slurm::JobRequest r;
      r.name = fmt::format("meltlab-{}-{}", e.name, j.wave_index);
      r.resources = {std::get<0>(res), std::get<1>(res), std::get<2>(res), std::get<3>(res)};
      r.array_size = j.array ? static_cast<int>(steps.size()) : 0;
      r.log = slurm / "logs" /
              (j.array ? fmt::format("job-{}_%a.log", j.wave_index) : fmt::format("job-{}.log", j.wave_index));
      r.workdir = fs::current_path();  // as a local step: relative paths mean the same
      r.exclusive = e.exclusive;
      r.extra_args = o.slurm.sbatch_args;
      r.script = slurm / fmt::format("job-{}.sh", j.wave_index);
      write_text_atomically(r.script, fmt::format("#!/bin/sh\n# written by meltlab reproduce --executor slurm ({})\n"
                                                  "exec {} run-job --plan {} --job {}\n",
                                                  e.name, slurm::shell_quote(o.self_exe.string()),
                                                  slurm::shell_quote(plan_file(e).string()), j.wave_index));
      jobs.push_back(j);
      requests.push_back(r);
    }
  // The plan first (a job may start before sbatch returns), then again with the job ids.
  write_text_atomically(plan_file(e), plan_json(o, e, jobs).dump(2) + "\n");
  std::vector<std::string> submitted;
  try {
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      // each wave waits for every job of the latest wave before it (which waited for theirs)
      int before = -1;
      for (std::size_t p = 0; p < i; ++p)
        if (jobs[p].wave < jobs[i].wave) before = std::max(before, jobs[p].wave);
      for (std::size_t p = 0; p < i; ++p)
        if (jobs[p].wave == before) requests[i].after_ok.push_back(jobs[p].id);
      jobs[i].id = slurm::submit(requests[i], slurm / ".sbatch.out");
      submitted.push_back(jobs[i].id);
    }
  } catch (const InputError&) {
    slurm::cancel(submitted, slurm / ".scancel.out");
    fs::remove(plan_file(e), ec);
    throw;
  }
  write_text_atomically(plan_file(e), plan_json(o, e, jobs).dump(2) + "\n");
  std::string ids;
  for (const auto& j : jobs)
    ids += fmt::format("{}{}{}", ids.empty() ? "" : ", ", j.id,
                       j.array ? fmt::format(" (array of {})", j.steps.size()) : "");
  say(fmt::format("{}: {} {} step(s) as Slurm job(s) {}", e.name, resume ? "resubmitted" : "submitted", todo.size(),
                  ids));
  return jobs;
}

/// The steps' outcomes from their records (config order; steps without a record left out).
std::vector<StepOutcome> recorded_steps(const ReproduceExperiment& e, double& first_start, double& last_finish) {
  std::vector<StepOutcome> steps;
  first_start = 0;
  last_finish = 0;
  for (const auto& s : e.steps) {
    const auto r = read_json(record_file(slurm_dir(e), s.name));
    if (!r || r->value("hash", "") != e.hash) continue;
    steps.push_back({s.name, r->value("exit_code", -1), r->value("seconds", 0.0)});
    const double a = r->value("started_unix", 0.0), b = r->value("finished_unix", 0.0);
    first_start = first_start == 0 ? a : std::min(first_start, a);
    last_finish = std::max(last_finish, b);
  }
  return steps;
}

/// All steps done: done.json, last (the local marker's keys, plus the executor and its jobs).
void write_done(const ReproduceOptions& o, const Tracked& t) {
  const ReproduceExperiment& e = *t.e;
  double a = 0, b = 0;
  t.out->steps = recorded_steps(e, a, b);
  t.out->seconds = b > a ? b - a : 0;
  t.out->status = "ran";
  json ids = json::array();
  for (const auto& j : t.jobs) ids.push_back(j.id);
  const json marker = {{"experiment", e.name},
                       {"hash", e.hash},
                       {"mode", o.quick ? "quick" : "full"},
                       {"finished", utc_timestamp_iso8601_now()},
                       {"seconds", t.out->seconds},
                       {"steps", steps_json(t.out->steps)},
                       {"config", e.config_file.string()},
                       {"executor", "slurm"},
                       {"slurm_jobs", ids}};
  write_text_atomically(e.out_dir / "done.json", marker.dump(2) + "\n");
}

/// Marks the plan as reported (the next run resumes instead of reporting again).
void mark_reported(const ReproduceExperiment& e) {
  if (auto plan = read_json(plan_file(e))) {
    (*plan)["reported"] = true;
    write_text_atomically(plan_file(e), plan->dump(2) + "\n");
  }
}

std::string describe(const slurm::TaskState& t) {
  std::string s = t.state.empty() ? "UNKNOWN" : t.state;
  if (!t.reason.empty() && t.reason != "None") s += " (" + t.reason + ")";
  if (!t.exit_code.empty() && t.exit_code != "0:0") s += ", exit " + t.exit_code;
  return s;
}

/// One poll of one experiment: progress lines for changed step states; when no task is
/// queued any more, the outcome (done.json, or failed with the first failed step's Slurm
/// state and logs).
void update(const ReproduceOptions& o, Tracked& t, const std::map<std::string, slurm::TaskState>& states,
            Counters& counters, const Say& say) {
  const ReproduceExperiment& e = *t.e;
  const fs::path slurm = slurm_dir(e);
  std::error_code ec;
  bool live = false;
  struct Failure {
    std::size_t step;
    std::string text;
  };
  std::vector<Failure> failures;
  bool waiting_for_record = false;
  for (const Job& j : t.jobs)
    for (std::size_t a = 0; a < j.steps.size(); ++a) {
      const std::size_t k = j.steps[a];
      const ReproduceStep& s = e.steps[k];
      const std::string task = j.task_id(a);
      const auto it = states.find(task);
      // A queued array whose tasks have not been split off yet is listed as "ID_[0-3]".
      const bool queued_whole = !states.count(task) && std::any_of(states.begin(), states.end(), [&](const auto& kv) {
        return kv.second.live && kv.first.rfind(j.id + "_[", 0) == 0;
      });
      std::string shown;
      if ((it != states.end() && it->second.live) || queued_whole) {
        live = true;
        shown = queued_whole ? "PENDING" : it->second.state;
      } else if (success_record(e, s.name)) {
        shown = "COMPLETED";
      } else {
        const auto rec = read_json(record_file(slurm, s.name));
        const slurm::TaskState st = it != states.end() ? it->second : slurm::TaskState{};
        if (!rec && st.state == "COMPLETED" && t.missing_records < 3) {
          waiting_for_record = true;  // a shared file system may show the record a little later
          continue;
        }
        shown = st.state.empty() ? "UNKNOWN" : st.state;
        const fs::path err = *step_process(o, e, s).stderr_file;
        std::string text = fmt::format("step {}: Slurm job {} {}", s.name, task, describe(st));
        if (rec && rec->value("hash", "") == e.hash)
          text += fmt::format(", step exited with code {}: {}", rec->value("exit_code", -1), last_line(err));
        else if (st.state.empty())
          text += " (no record of the step: the job ended before it finished)";
        std::string logs;
        for (const fs::path& log : {err, j.log(slurm, a)})
          if (fs::exists(log, ec)) logs += (logs.empty() ? "" : ", ") + log.string();
        text += logs.empty() ? std::string(" (the job never started: no logs)") : " (logs: " + logs + ")";
        failures.push_back({k, text});
      }
      if (t.shown[k] != shown) {
        t.shown[k] = shown;
        std::string where;
        if (shown == "RUNNING" || shown == "COMPLETED")
          if (const auto rec = read_json(record_file(slurm, s.name)))
            where = fmt::format(" on {}", rec->value(json::json_pointer("/provenance/hardware/host"), std::string()));
        say(fmt::format("{}: step {}/{} {}: {} (Slurm job {}{})", e.name, k + 1, e.steps.size(), s.name, shown, task,
                        where));
      }
    }
  if (live) return;
  if (waiting_for_record) {
    ++t.missing_records;
    return;
  }
  t.terminal = true;
  --counters.running;
  ++counters.finished;
  if (failures.empty()) {
    write_done(o, t);
    say(fmt::format("{}: done on Slurm ({:.1f} s from the first step's start to the last one's end)", e.name,
                    t.out->seconds));
    return;
  }
  std::sort(failures.begin(), failures.end(), [](const auto& x, const auto& y) { return x.step < y.step; });
  double a = 0, b = 0;
  t.out->steps = recorded_steps(e, a, b);
  t.out->seconds = b > a ? b - a : 0;
  t.out->status = "failed";
  t.out->error = failures.front().text;
  if (failures.size() > 1) t.out->error += fmt::format(" (and {} more step(s) not done)", failures.size() - 1);
  ++counters.failed;
  mark_reported(e);
  say(fmt::format("{}: FAILED on Slurm: {}", e.name, t.out->error));
}

/// Whether any job of `plan` is still queued (a check before a new submission replaces it).
std::vector<std::string> queued_jobs(const json& plan, const fs::path& scratch) {
  std::vector<std::string> ids;
  for (const auto& j : plan.value("jobs", json::array()))
    if (j.contains("id") && j["id"].is_string()) ids.push_back(j["id"].get<std::string>());
  std::vector<std::string> live;
  for (const auto& [task, st] : slurm::query(ids, scratch))
    if (st.live && std::find(live.begin(), live.end(), slurm::job_of_task(task)) == live.end())
      live.push_back(slurm::job_of_task(task));
  return live;
}

}  // namespace

void run_on_slurm(const ReproduceOptions& o, const std::vector<ReproduceExperiment>& experiments,
                  std::vector<ExperimentOutcome>& outcomes, Counters& counters, const Say& say,
                  const std::atomic<bool>* stop) {
  std::vector<Tracked> tracked;
  const fs::path scratch = o.out_dir / ".slurm-query.out";
  for (std::size_t i = 0; i < experiments.size(); ++i) {
    const ReproduceExperiment& e = experiments[i];
    ExperimentOutcome& out = outcomes[i];
    out.name = e.name;
    out.title = e.title;
    out.hash = e.hash;
    if (stop && stop->load()) break;
    try {
      if (!o.force)
        if (std::optional<ExperimentOutcome> reused = read_finished(e)) {
          out = std::move(*reused);
          out.status = "reused";
          ++counters.finished;
          say(fmt::format("{}: reused (finished earlier in {:.1f} s)", out.name, out.original_seconds));
          continue;
        }
      const std::optional<json> plan = read_json(plan_file(e));
      Tracked t;
      t.e = &e;
      t.out = &out;
      if (plan && plan->value("hash", "") == e.hash && !plan->value("reported", false) && !o.force) {
        t.jobs = plan_jobs(*plan, e);
        say(fmt::format("{}: collecting the Slurm jobs submitted {}", e.name, plan->value("submitted_utc", "earlier")));
      } else {
        if (plan) {
          const auto live = queued_jobs(*plan, scratch);
          if (!live.empty()) {
            std::string ids;
            for (const auto& id : live) ids += (ids.empty() ? "" : " ") + id;
            throw InputError(
                fmt::format("Slurm jobs of an earlier submission of this experiment are still queued "
                            "({}): wait for them or cancel them (scancel {})",
                            ids, ids));
          }
        }
        const bool resume = plan && plan->value("hash", "") == e.hash && !o.force && fs::exists(e.out_dir);
        t.jobs = submit_experiment(o, e, resume, say);
      }
      out.status = "submitted";
      ++counters.running;
      // every step already has its record (a failure reported before a slow file system showed
      // the last records): nothing to submit, collect it now
      if (t.jobs.empty()) update(o, t, {}, counters, say);
      tracked.push_back(std::move(t));
    } catch (const std::exception& ex) {
      out.status = "failed";
      out.error = ex.what();
      ++counters.finished;
      ++counters.failed;
      say(fmt::format("{}: FAILED: {}", e.name, out.error));
    }
  }
  if (o.slurm.detach) {
    if (!tracked.empty())
      say(
          fmt::format("detached: {} experiment(s) on Slurm; run the same command again (without --detach) to wait "
                      "for them, collect them and build the report",
                      tracked.size()));
    return;
  }
  using Clock = std::chrono::steady_clock;
  int query_failures = 0;
  for (;;) {
    std::vector<std::string> ids;
    for (const auto& t : tracked)
      if (!t.terminal)
        for (const auto& j : t.jobs) ids.push_back(j.id);
    if (ids.empty()) break;
    std::map<std::string, slurm::TaskState> states;
    try {
      states = slurm::query(ids, scratch);
      query_failures = 0;
    } catch (const InputError& ex) {
      if (query_failures++ == 0) say(fmt::format("Slurm: {} (retrying)", ex.what()));
      states.clear();
    }
    if (query_failures == 0)
      for (auto& t : tracked)
        if (!t.terminal) update(o, t, states, counters, say);
    if (std::all_of(tracked.begin(), tracked.end(), [](const Tracked& t) { return t.terminal; })) break;
    const auto until = Clock::now() + std::chrono::duration<double>(o.slurm.poll_seconds);
    while (Clock::now() < until && !(stop && stop->load())) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (stop && stop->load()) {
      say("interrupted: the Slurm jobs go on; run the same command again to collect them");
      return;
    }
  }
  std::error_code ec;
  fs::remove(scratch, ec);
}

}  // namespace reproduce_detail

int run_slurm_job(const fs::path& plan_path, std::size_t job_index, const std::vector<std::string>& command_line) {
  const json plan = json::parse(read_text_file(plan_path, "Slurm plan"));
  const json& jobs = plan.at("jobs");
  if (job_index >= jobs.size())
    throw InputError(fmt::format("{}: no job {} (the plan has {})", plan_path.string(), job_index, jobs.size()));
  const json& job = jobs[job_index];
  std::size_t task = 0;
  if (job.at("array").get<bool>()) {
    const char* a = std::getenv("SLURM_ARRAY_TASK_ID");
    if (!a) throw InputError("run-job: an array job needs SLURM_ARRAY_TASK_ID (run by Slurm)");
    task = std::stoul(a);
  }
  const auto& names = job.at("steps");
  if (task >= names.size()) throw InputError(fmt::format("run-job: array task {} out of range", task));
  const std::string name = names[task].get<std::string>();
  const json* step = nullptr;
  for (const auto& s : plan.at("steps"))
    if (s.at("name") == name) step = &s;
  if (!step) throw InputError(fmt::format("{}: no step '{}'", plan_path.string(), name));

  Provenance provenance = start_provenance("run-job", command_line);
  ProcessSpec spec;
  spec.argv = step->at("argv").get<std::vector<std::string>>();
  spec.search_path = step->at("search_path").get<bool>();
  spec.stdin_file = kNullDevice;
  spec.stdout_file = step->at("stdout").get<std::string>();
  spec.stderr_file = step->at("stderr").get<std::string>();
  std::error_code ec;
  fs::remove(record_file(plan_path.parent_path(), name), ec);
  for (const auto& p : step->value("clear", json::array())) fs::remove_all(p.get<std::string>(), ec);
  fs::create_directories(spec.stdout_file->parent_path());
  fs::create_directories(spec.stderr_file->parent_path());
  const double started = unix_now();
  const auto t0 = std::chrono::steady_clock::now();
  const int code = run_process(spec).shell_status();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const json record = {{"experiment", plan.at("experiment")},
                       {"step", name},
                       {"hash", plan.at("hash")},
                       {"exit_code", code},
                       {"seconds", seconds},
                       {"started_unix", started},
                       {"finished_unix", unix_now()},
                       {"provenance", finish_provenance(provenance)}};
  write_text_atomically(record_file(plan_path.parent_path(), name), record.dump(2) + "\n");
  return code == 0 ? 0 : std::clamp(code, 1, 255);
}

}  // namespace meltlab::experiments
