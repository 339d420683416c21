#include <meltlab/core/config.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/reproduce.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/process.h>
#include <meltlab/core/time.h>
#include <meltlab/version.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

namespace meltlab::experiments {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

/// The Python files in the folder of `script` and below it, sorted (the modules it may import).
std::vector<fs::path> python_modules_beside(const fs::path& script) {
  std::vector<fs::path> modules;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(script.parent_path(), ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && it->path().extension() == ".py" && it->path() != script) modules.push_back(it->path());
  std::sort(modules.begin(), modules.end());
  return modules;
}

using Clock = std::chrono::steady_clock;

std::string read_file(const fs::path& p) { return read_text_file(p, "experiment"); }

bool valid_name(const std::string& s) {
  static const std::regex re("[a-z0-9_]+");
  return std::regex_match(s, re);
}

/// Replaces ${var} in `s`; unknown names are an error naming the config.
std::string substitute(const std::string& s, const std::map<std::string, std::string>& vars, const fs::path& config) {
  std::string out;
  std::size_t i = 0;
  while (i < s.size()) {
    const auto open = s.find("${", i);
    if (open == std::string::npos) {
      out += s.substr(i);
      break;
    }
    const auto close = s.find('}', open);
    if (close == std::string::npos) throw InputError(fmt::format("{}: unterminated '${{' in '{}'", config.string(), s));
    out += s.substr(i, open - i);
    const std::string key = s.substr(open + 2, close - open - 2);
    const auto it = vars.find(key);
    if (it == vars.end()) throw InputError(fmt::format("{}: unknown variable '${{{}}}' in '{}'", config.string(), key, s));
    out += it->second;
    i = close + 1;
  }
  return out;
}

/// The texts of a list of scalars.
std::vector<std::string> texts(const ConfigValue& list) {
  std::vector<std::string> out;
  for (const ConfigValue& item : list.items()) out.push_back(item.as<std::string>());
  return out;
}

ReproduceExperiment load_one(const fs::path& config, const ReproduceOptions& o) {
  const std::string text = read_file(config);
  const ConfigSection root(parse_yaml_text(text, config.string()), config.string());
  ReproduceExperiment e;
  e.config_file = config;
  e.name = root.require<std::string>("name");
  if (!valid_name(e.name) || e.name == "report" || e.name == "logs")
    root.fail_at("name", fmt::format("name '{}' must be [a-z0-9_]+ and not 'report' or 'logs'", e.name));
  e.title = root.get("title", e.name);
  if (const auto sources = root.optional_value("sources")) e.sources = texts(*sources);
  root.ignore("notes");  // free text for whoever reads the config
  e.out_dir = o.out_dir / e.name;
  e.exclusive = root.get("exclusive", e.exclusive);

  const std::string mode = o.quick ? "quick" : "full";
  if (const auto modes = root.optional_value("modes")) {
    if (!modes->is_sequence() || modes->items().empty()) modes->fail("must be a non-empty list of quick and/or full");
    e.modes.clear();
    for (const ConfigValue& m : modes->items()) {
      const std::string v = m.as<std::string>();
      if (v != "quick" && v != "full") m.fail(fmt::format("must be quick or full (got '{}')", v));
      e.modes.push_back(v);
    }
  }
  e.in_mode = std::find(e.modes.begin(), e.modes.end(), mode) != e.modes.end();
  std::map<std::string, std::string> vars{{"out", e.out_dir.string()},
                                          {"repo", o.source_dir.string()},
                                          {"config_dir", config.parent_path().string()},
                                          {"bin", o.self_exe.parent_path().string()},
                                          {"mode", mode}};
  if (const auto var_section = root.optional_section("vars")) {
    for (const std::string& key : var_section->keys()) {
      if (vars.count(key) || key == "step") var_section->fail_at(key, fmt::format("var '{}' is reserved", key));
      const ConfigValue v = var_section->value(key);
      if (!v.is_map()) {
        vars[key] = v.as<std::string>();
        continue;
      }
      // {quick: a, full: b}: this mode's value; the other one must be there too.
      const ConfigSection by_mode = v.section();
      if (!by_mode.has("quick") || !by_mode.has("full")) v.fail("needs both 'quick' and 'full'");
      vars[key] = by_mode.require<std::string>(mode);
      by_mode.ignore(mode == "quick" ? "full" : "quick");
    }
  }
  auto resolve = [&](const std::string& p) {
    const fs::path path(p);
    return path.is_absolute() ? path : o.source_dir / path;
  };
  if (const auto inputs = root.optional_value("inputs"))
    for (const ConfigValue& in : inputs->items()) {
      const fs::path p = resolve(substitute(in.as<std::string>(), vars, config));
      if (!fs::is_regular_file(p)) in.fail(fmt::format("input '{}' does not exist", p.string()));
      e.hashed_files.push_back(p);
    }
  if (!root.has("steps")) root.fail("missing key 'steps' (a non-empty list)");
  const std::vector<ConfigValue> steps = root.value("steps").items();
  if (steps.empty()) root.fail_at("steps", "'steps' must be a non-empty list");
  std::set<std::string> step_names;
  for (const ConfigValue& item : steps) {
    const ConfigSection s = item.section();
    ReproduceStep step;
    if (!s.has("name")) s.fail("every step needs a 'name'");
    step.name = s.require<std::string>("name");
    if (!valid_name(step.name) || !step_names.insert(step.name).second)
      s.fail_at("name", fmt::format("step name '{}' must be [a-z0-9_]+ and unique", step.name));
    if (s.has("meltlab") == s.has("python")) s.fail(fmt::format("step '{}' needs exactly one of 'meltlab' and 'python'", step.name));
    step.kind = s.has("meltlab") ? "meltlab" : "python";
    const ConfigValue args = s.value(step.kind);
    if (!args.is_sequence() || args.items().empty())
      args.fail(fmt::format("step '{}': '{}' must be a non-empty list", step.name, step.kind));
    auto step_vars = vars;
    step_vars["step"] = (e.out_dir / step.name).string();
    for (const std::string& a : texts(args)) step.args.push_back(substitute(a, step_vars, config));
    if (step.kind == "python") {
      step.args[0] = resolve(step.args[0]).string();
      if (!fs::is_regular_file(step.args[0]))
        args.fail(fmt::format("step '{}': script '{}' does not exist", step.name, step.args[0]));
      // A script imports its siblings (report/experiment_report.py dispatches to
      // report/experiments/<kind>.py): every Python file of its folder is an input too.
      for (const fs::path& module : python_modules_beside(step.args[0])) e.hashed_files.push_back(module);
    }
    if (const auto out = s.optional<std::string>("stdout")) step.stdout_file = substitute(*out, step_vars, config);
    // Files named by the arguments (a mesh, a kl field, a script) are inputs too; what lies
    // under the output folder is not.
    for (const auto& a : step.args) {
      std::error_code ec;
      const fs::path p(a);
      if (!p.is_absolute() || !fs::is_regular_file(p, ec)) continue;
      const auto rel = fs::relative(p, o.out_dir, ec);
      if (!ec && !rel.empty() && rel.begin()->string() != "..") continue;
      e.hashed_files.push_back(p);
    }
    e.steps.push_back(std::move(step));
  }
  root.finish();

  ContentHash f;
  f.add_field("meltlab-reproduce-2");
  f.add_field(kVersion);
  f.add_field(kGitRevision);
  f.add_field(mode);
  f.add_field(text);
  for (const auto& step : e.steps)
    for (const auto& a : step.args) f.add_field(a);
  for (const auto& p : e.hashed_files) {
    f.add_field(p.string());
    f.add_field(read_file(p));
  }
  e.hash = f.hex();
  return e;
}

std::string last_line(const fs::path& p) {
  std::ifstream in(p);
  std::string line, last;
  while (std::getline(in, line)) {
    // the progress line of a tty run is never written to a file, but strip \r just in case
    if (const auto cr = line.rfind('\r'); cr != std::string::npos) line = line.substr(cr + 1);
    if (!line.empty()) last = line;
  }
  return last;
}

std::string quote_join(const std::vector<std::string>& args) {
  std::string s;
  for (const auto& a : args) s += (s.empty() ? "" : " ") + (a.find(' ') == std::string::npos ? a : "'" + a + "'");
  return s;
}

}  // namespace

std::vector<ReproduceExperiment> load_reproduce_experiments(const ReproduceOptions& o) {
  std::vector<fs::path> files;
  for (const auto& dir : o.config_dirs) {
    if (!fs::is_directory(dir)) throw InputError(fmt::format("--configs: '{}' is not a folder", dir.string()));
    for (const auto& entry : fs::directory_iterator(dir))
      if (entry.is_regular_file() && (entry.path().extension() == ".yaml" || entry.path().extension() == ".yml"))
        files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<ReproduceExperiment> all;
  std::set<std::string> names;
  for (const auto& f : files) {
    ReproduceExperiment e = load_one(f, o);
    if (!names.insert(e.name).second) throw InputError(fmt::format("{}: experiment name '{}' used twice", f.string(), e.name));
    all.push_back(std::move(e));
  }
  if (o.only.empty()) {
    all.erase(std::remove_if(all.begin(), all.end(), [](const auto& e) { return !e.in_mode; }), all.end());
    return all;
  }
  std::vector<ReproduceExperiment> picked;
  for (const auto& want : o.only) {
    auto it = std::find_if(all.begin(), all.end(), [&](const auto& e) { return e.name == want; });
    if (it == all.end()) {
      std::string known;
      for (const auto& e : all) known += (known.empty() ? "" : ", ") + e.name;
      throw InputError(fmt::format("--only: no experiment '{}' (known: {})", want, known));
    }
    if (!it->in_mode)
      throw InputError(fmt::format("--only: experiment '{}' runs only in {} mode", want, it->modes.front()));
    if (std::none_of(picked.begin(), picked.end(), [&](const auto& p) { return p.name == want; })) picked.push_back(*it);
  }
  return picked;
}

ReproduceResult run_reproduce(const ReproduceOptions& o, const std::vector<ReproduceExperiment>& experiments,
                              const std::function<void(const std::string&)>& log, const std::atomic<bool>* stop) {
  fs::create_directories(o.out_dir);
  const auto t0 = Clock::now();
  std::mutex mu;
  std::size_t finished = 0, failed = 0, running = 0;
  ReproduceResult result;
  result.experiments.resize(experiments.size());
  auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  auto say = [&](const std::string& msg) {  // caller holds mu
    log(fmt::format("[{:6.1f}s {}/{} done, {} running, {} failed] {}", elapsed(), finished, experiments.size(), running,
                    failed, msg));
  };

  auto run_one = [&](const ReproduceExperiment& e, ExperimentOutcome& out) {
    out.name = e.name;
    out.title = e.title;
    out.hash = e.hash;
    const fs::path done = e.out_dir / "done.json";
    if (!o.force && fs::exists(done)) {
      try {
        const json d = json::parse(read_file(done));
        if (d.value("hash", "") == e.hash) {
          out.status = "reused";
          out.original_seconds = d.value("seconds", 0.0);
          for (const auto& s : d.value("steps", json::array()))
            out.steps.push_back({s.value("name", ""), s.value("exit_code", 0), s.value("seconds", 0.0)});
          return;
        }
      } catch (const std::exception&) {
        // an unreadable marker means the folder is redone
      }
    }
    const auto te = Clock::now();
    std::error_code ec;
    fs::remove_all(e.out_dir, ec);
    fs::create_directories(e.out_dir / "logs");
    for (std::size_t k = 0; k < e.steps.size(); ++k) {
      const auto& s = e.steps[k];
      if (stop && stop->load()) {
        out.status = "failed";
        out.error = "interrupted";
        break;
      }
      std::vector<std::string> argv;
      if (s.kind == "meltlab") {
        argv.push_back(o.self_exe.string());
      } else {
        argv.push_back(o.python);
      }
      argv.insert(argv.end(), s.args.begin(), s.args.end());
      {
        std::lock_guard lock(mu);
        say(fmt::format("{}: step {}/{} {}: {}", e.name, k + 1, e.steps.size(), s.name,
                        s.kind == "meltlab" ? "meltlab " + quote_join(s.args) : "python " + quote_join(s.args)));
      }
      const fs::path out_file = s.stdout_file.empty() ? e.out_dir / "logs" / (s.name + ".out") : s.stdout_file;
      const fs::path err_file = e.out_dir / "logs" / (s.name + ".err");
      const auto ts = Clock::now();
      int code = -1;
      try {
        fs::create_directories(out_file.parent_path());
        ProcessSpec spec;
        spec.argv = argv;
        spec.search_path = s.kind == "python";  // meltlab is started by its absolute path
        spec.stdin_file = kNullDevice;
        spec.stdout_file = out_file;
        spec.stderr_file = err_file;
        code = run_process(spec).shell_status();
      } catch (const std::exception& ex) {
        out.error = fmt::format("step {}: {}", s.name, ex.what());
      }
      out.steps.push_back({s.name, code, std::chrono::duration<double>(Clock::now() - ts).count()});
      if (code != 0) {
        out.status = "failed";
        if (out.error.empty())
          out.error = fmt::format("step {} ({} {}) exited with code {}: {}", s.name, s.kind, s.args.empty() ? "" : s.args[0],
                                  code, last_line(err_file));
        break;
      }
    }
    out.seconds = std::chrono::duration<double>(Clock::now() - te).count();
    if (out.status == "failed") return;
    out.status = "ran";
    json steps = json::array();
    for (const auto& s : out.steps) steps.push_back({{"name", s.name}, {"exit_code", s.exit_code}, {"seconds", s.seconds}});
    const json marker = {{"experiment", e.name}, {"hash", e.hash},       {"mode", o.quick ? "quick" : "full"},
                         {"finished", utc_timestamp_iso8601_now()}, {"seconds", out.seconds}, {"steps", steps},
                         {"config", e.config_file.string()}};
    write_text_atomically(done, marker.dump(2) + "\n");  // last: the folder is complete
  };

  // Exclusive experiments (timing measurements) run first, one at a time, alone; the others
  // then share the workers.
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
        say(fmt::format("{}: reused (finished earlier in {:.1f} s)", out.name, out.original_seconds));
      else if (out.status == "failed")
        say(fmt::format("{}: FAILED after {:.1f} s: {}", out.name, out.seconds, out.error));
      else
        say(fmt::format("{}: done in {:.1f} s", out.name, out.seconds));
    }
  };
  const int jobs = std::max(1, std::min<int>(o.jobs, static_cast<int>(std::max<std::size_t>(1, experiments.size()))));
  worker();  // the exclusive ones, on this thread
  next = 0;
  queue = &shared;
  std::vector<std::thread> pool;
  for (int j = 0; j < jobs; ++j) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  for (std::size_t i = 0; i < experiments.size(); ++i)
    if (result.experiments[i].status.empty()) {
      result.experiments[i].name = experiments[i].name;
      result.experiments[i].title = experiments[i].title;
      result.experiments[i].status = "not run";
      result.experiments[i].error = "interrupted before it started";
    }
  result.interrupted = stop && stop->load();
  result.seconds = elapsed();
  // Experiments not selected this time (--only) whose folders are finished with the current
  // hash stay in the summary and the report as "kept".
  std::vector<const ReproduceExperiment*> listed;
  for (const auto& e : experiments) listed.push_back(&e);
  if (!o.only.empty()) {
    auto all_options = o;
    all_options.only.clear();
    for (const auto& e : load_reproduce_experiments(all_options)) {
      if (std::find(o.only.begin(), o.only.end(), e.name) != o.only.end()) continue;
      try {
        const json d = json::parse(read_file(e.out_dir / "done.json"));
        if (d.value("hash", "") != e.hash) continue;
        ExperimentOutcome k;
        k.name = e.name;
        k.title = e.title;
        k.status = "kept";
        k.hash = e.hash;
        k.original_seconds = d.value("seconds", 0.0);
        for (const auto& st : d.value("steps", json::array()))
          k.steps.push_back({st.value("name", ""), st.value("exit_code", 0), st.value("seconds", 0.0)});
        result.experiments.push_back(k);
        result.kept.push_back(e);
      } catch (const std::exception&) {
        // no finished folder: not listed
      }
    }
    for (const auto& e : result.kept) listed.push_back(&e);
  }

  auto summary_json = [&] {
    json ex = json::array();
    for (std::size_t i = 0; i < listed.size(); ++i) {
      const auto& r = result.experiments[i];
      const ReproduceExperiment& x = *listed[i];
      json steps = json::array();
      for (const auto& s : r.steps) steps.push_back({{"name", s.name}, {"exit_code", s.exit_code}, {"seconds", s.seconds}});
      ex.push_back({{"name", r.name},
                    {"title", r.title},
                    {"sources", x.sources},
                    {"status", r.status},
                    {"error", r.error},
                    {"seconds", r.seconds},
                    {"original_seconds", r.original_seconds},
                    {"steps", steps},
                    {"hash", x.hash},
                    {"exclusive", x.exclusive},
                    {"config", x.config_file.string()},
                    {"folder", x.name}});
    }
    return json{{"meltlab", {{"version", kVersion}, {"git_revision", kGitRevision}}},
                {"mode", o.quick ? "quick" : "full"},
                {"jobs", jobs},
                {"finished", utc_timestamp_iso8601_now()},
                {"seconds", result.seconds},
                {"interrupted", result.interrupted},
                {"experiments", ex}};
  };
  write_text_atomically(o.out_dir / "summary.json", summary_json().dump(2) + "\n");

  result.report_status = "skipped";
  if (o.report && !result.interrupted) {
    const fs::path script = o.source_dir / "report" / "build_report.py";
    const fs::path log_out = o.out_dir / "build_report.out", log_err = o.out_dir / "build_report.err";
    {
      std::lock_guard lock(mu);
      say(fmt::format("report: python {} {}", script.string(), o.out_dir.string()));
    }
    int code = -1;
    try {
      ProcessSpec spec;
      spec.argv = {o.python, script.string(), o.out_dir.string()};
      spec.stdin_file = kNullDevice;
      spec.stdout_file = log_out;
      spec.stderr_file = log_err;
      code = run_process(spec).shell_status();
    } catch (const std::exception& ex) {
      result.report_status = fmt::format("failed: {}", ex.what());
    }
    if (code == 0) {
      result.report_status = "built";
      result.report_file = o.out_dir / "report" / "index.html";
    } else if (result.report_status == "skipped") {
      result.report_status = fmt::format("failed: exit {}: {}", code, last_line(log_err));
    }
  }
  return result;
}

}  // namespace meltlab::experiments
