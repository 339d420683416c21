// meltlab reproduce, stage 1: the experiment configs (format: meltlab/experiments/reproduce.h).
#include "stages.h"

#include <meltlab/core/config.h>
#include <meltlab/core/error.h>
#include <meltlab/core/hash.h>
#include <meltlab/core/input_file.h>
#include <meltlab/version.h>

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <regex>
#include <set>

namespace meltlab::experiments {
namespace fs = std::filesystem;

namespace {

using Vars = std::map<std::string, std::string>;

std::string read_file(const fs::path& p) { return read_text_file(p, "experiment"); }

bool valid_name(const std::string& s) {
  static const std::regex re("[a-z0-9_]+");
  return std::regex_match(s, re);
}

/// Replaces ${var} in `s`; unknown names are an error naming the config.
std::string substitute(const std::string& s, const Vars& vars, const fs::path& config) {
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
    if (it == vars.end())
      throw InputError(fmt::format("{}: unknown variable '${{{}}}' in '{}'", config.string(), key, s));
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

/// The Python files in the folder of `script` and below it, sorted (the modules it may import).
std::vector<fs::path> python_modules_beside(const fs::path& script) {
  std::vector<fs::path> modules;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(script.parent_path(), ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && it->path().extension() == ".py" && it->path() != script)
      modules.push_back(it->path());
  std::sort(modules.begin(), modules.end());
  return modules;
}

/// A path of a config: absolute as written, otherwise relative to the repository.
fs::path resolve(const std::string& p, const ReproduceOptions& o) {
  const fs::path path(p);
  return path.is_absolute() ? path : o.source_dir / path;
}

/// `modes:` (default both); sets e.modes and e.in_mode.
void read_modes(const ConfigSection& root, const std::string& mode, ReproduceExperiment& e) {
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
}

/// The reserved variables and the config's `vars:` (a scalar, or {quick, full} by mode).
Vars read_vars(const ConfigSection& root, const fs::path& config, const std::string& mode, const ReproduceExperiment& e,
               const ReproduceOptions& o) {
  Vars vars{{"out", e.out_dir.string()},
            {"repo", o.source_dir.string()},
            {"config_dir", config.parent_path().string()},
            {"bin", o.self_exe.parent_path().string()},
            {"mode", mode}};
  const auto var_section = root.optional_section("vars");
  if (!var_section) return vars;
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
  return vars;
}

/// A `slurm:` mapping (experiment or step level): partition, time, cpus, mem.
SlurmResources read_slurm(const ConfigSection& s) {
  SlurmResources r;
  static const std::regex partition_re("[A-Za-z0-9_.,-]+"), time_re("[0-9]+([-:][0-9]+)*"), mem_re("[0-9]+[KMGT]?");
  r.partition = s.get<std::string>("partition", "");
  if (s.has("partition") && !std::regex_match(r.partition, partition_re))
    s.fail_at("partition", fmt::format("'{}' is not a Slurm partition name", r.partition));
  r.time = s.get<std::string>("time", "");
  if (s.has("time") && !std::regex_match(r.time, time_re))
    s.fail_at("time", fmt::format("'{}' is not a Slurm time limit (minutes, H:MM:SS or D-HH:MM:SS)", r.time));
  r.cpus = s.get_in_range("cpus", 0, 1, 4096);
  r.mem = s.get<std::string>("mem", "");
  if (s.has("mem") && !std::regex_match(r.mem, mem_re))
    s.fail_at("mem", fmt::format("'{}' is not a Slurm memory size (a number with K, M, G or T)", r.mem));
  return r;
}

/// One entry of `steps:`; adds the files it names (script, its sibling modules, file
/// arguments outside the output folder) to e.hashed_files.
ReproduceStep read_step(const ConfigValue& item, const Vars& vars, const fs::path& config, const ReproduceOptions& o,
                        const SlurmResources& e_slurm, std::set<std::string>& step_names, ReproduceExperiment& e) {
  const ConfigSection s = item.section();
  ReproduceStep step;
  if (!s.has("name")) s.fail("every step needs a 'name'");
  step.name = s.require<std::string>("name");
  if (!valid_name(step.name) || !step_names.insert(step.name).second)
    s.fail_at("name", fmt::format("step name '{}' must be [a-z0-9_]+ and unique", step.name));
  if (step.name == "logs" || step.name == "slurm")  // the folders of the run's logs and Slurm records
    s.fail_at("name", fmt::format("step name '{}' is reserved", step.name));
  if (s.has("meltlab") == s.has("python"))
    s.fail(fmt::format("step '{}' needs exactly one of 'meltlab' and 'python'", step.name));
  step.kind = s.has("meltlab") ? "meltlab" : "python";
  const ConfigValue args = s.value(step.kind);
  if (!args.is_sequence() || args.items().empty())
    args.fail(fmt::format("step '{}': '{}' must be a non-empty list", step.name, step.kind));
  auto step_vars = vars;
  step_vars["step"] = (e.out_dir / step.name).string();
  for (const std::string& a : texts(args)) step.args.push_back(substitute(a, step_vars, config));
  if (step.kind == "python") {
    step.args[0] = resolve(step.args[0], o).string();
    if (!fs::is_regular_file(step.args[0]))
      args.fail(fmt::format("step '{}': script '{}' does not exist", step.name, step.args[0]));
    // A script imports its siblings (report/experiment_report.py dispatches to
    // report/experiments/<kind>.py): every Python file of its folder is an input too.
    for (const fs::path& module : python_modules_beside(step.args[0])) e.hashed_files.push_back(module);
  }
  if (const auto out = s.optional<std::string>("stdout")) step.stdout_file = substitute(*out, step_vars, config);
  const auto slurm = s.optional_section("slurm");
  step.slurm = e_slurm.overridden_by(slurm ? read_slurm(*slurm) : SlurmResources{});
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
  return step;
}

/// Whether `p` is `dir` or lies inside it (both lexically normal, absolute).
bool within(const fs::path& p, const fs::path& dir) {
  auto d = dir.begin();
  for (auto it = p.begin(); d != dir.end(); ++it, ++d)
    if (it == p.end() || *it != *d) return false;
  return true;
}

/// The step dependencies and waves (rules in reproduce.h).
void assign_waves(ReproduceExperiment& e) {
  const fs::path out = e.out_dir.lexically_normal();
  const std::string out_text = out.string();
  for (std::size_t k = 0; k < e.steps.size(); ++k) {
    ReproduceStep& s = e.steps[k];
    std::set<std::size_t> deps;
    auto all_before = [&] {
      for (std::size_t j = 0; j < k; ++j) deps.insert(j);
    };
    if (s.kind == "python") all_before();
    std::vector<std::string> texts = s.args;
    if (!s.stdout_file.empty()) texts.push_back(s.stdout_file.string());
    for (const std::string& a : texts)
      for (auto pos = a.find(out_text); pos != std::string::npos; pos = a.find(out_text, pos + 1)) {
        // the path from the folder's name to the end of the argument ("--x=${out}/a" too)
        const fs::path p = fs::path(a.substr(pos)).lexically_normal();
        if (!within(p, out)) continue;  // a longer name that starts alike (${out}_b)
        if (within(p, out / s.name)) continue;
        if (!s.stdout_file.empty() && p == s.stdout_file.lexically_normal() && a == s.stdout_file.string()) continue;
        bool known = false;
        for (std::size_t j = 0; j < k; ++j) {
          const ReproduceStep& o = e.steps[j];
          const fs::path folder = out / o.name;
          const fs::path file = o.stdout_file.empty() ? fs::path() : o.stdout_file.lexically_normal();
          if (within(p, folder) || within(folder, p) || (!file.empty() && (p == file || within(file, p)))) {
            deps.insert(j);
            known = true;
          }
        }
        // under ${out} but nobody's: it may be anything an earlier step wrote
        if (!known) all_before();
      }
    s.depends_on.assign(deps.begin(), deps.end());
    s.wave = 0;
    for (const std::size_t j : s.depends_on) s.wave = std::max(s.wave, e.steps[j].wave + 1);
  }
}

/// The content hash that decides whether a finished folder is reused: config text, mode,
/// meltlab version, the substituted arguments and every hashed file (name and content).
std::string experiment_hash(const ReproduceExperiment& e, const std::string& config_text, const std::string& mode) {
  ContentHash f;
  f.add_field("meltlab-reproduce-2");
  f.add_field(kVersion);
  f.add_field(kGitRevision);
  f.add_field(mode);
  f.add_field(config_text);
  for (const auto& step : e.steps)
    for (const auto& a : step.args) f.add_field(a);
  for (const auto& p : e.hashed_files) {
    f.add_field(p.string());
    // The file as one field (bytes, then "|size|"), streamed: hashed files include programs
    // (${bin}/meltlab; an ASan build's is over 700 MB), which are neither text nor small.
    check_input_file(p, "experiment input");
    f.add_file(p);
    f.add_bytes(fmt::format("|{}|", fs::file_size(p)));
  }
  return f.hex();
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
  read_modes(root, mode, e);
  const Vars vars = read_vars(root, config, mode, e, o);
  if (const auto inputs = root.optional_value("inputs"))
    for (const ConfigValue& in : inputs->items()) {
      const fs::path p = resolve(substitute(in.as<std::string>(), vars, config), o);
      if (!fs::is_regular_file(p)) in.fail(fmt::format("input '{}' does not exist", p.string()));
      e.hashed_files.push_back(p);
    }
  const auto slurm = root.optional_section("slurm");
  const SlurmResources e_slurm = slurm ? read_slurm(*slurm) : SlurmResources{};
  if (root.has("sweep")) {
    // the experiment is a sweep (meltlab/experiments/sweep.h): its points, collect and figures
    if (root.has("steps")) root.fail("has both 'steps' and 'sweep' (a sweep brings its own steps)");
    const fs::path file = resolve(substitute(root.require<std::string>("sweep"), vars, config), o);
    if (!fs::is_regular_file(file)) root.fail_at("sweep", fmt::format("sweep '{}' does not exist", file.string()));
    reproduce_detail::add_sweep_steps(load_sweep(file), o, e);
    for (auto& step : e.steps) step.slurm = e_slurm.overridden_by(step.slurm);
    root.finish();
    assign_waves(e);
    e.hash = experiment_hash(e, text, mode);
    return e;
  }
  if (!root.has("steps")) root.fail("missing key 'steps' (a non-empty list)");
  const std::vector<ConfigValue> steps = root.value("steps").items();
  if (steps.empty()) root.fail_at("steps", "'steps' must be a non-empty list");
  std::set<std::string> step_names;
  for (const ConfigValue& item : steps) e.steps.push_back(read_step(item, vars, config, o, e_slurm, step_names, e));
  root.finish();
  assign_waves(e);
  e.hash = experiment_hash(e, text, mode);
  return e;
}

}  // namespace

namespace reproduce_detail {
std::string content_hash(const ReproduceExperiment& e, const std::string& config_text, const std::string& mode) {
  return experiment_hash(e, config_text, mode);
}
void find_waves(ReproduceExperiment& e) { assign_waves(e); }
SlurmResources slurm_section(const ConfigSection& s) { return read_slurm(s); }
}  // namespace reproduce_detail

SlurmResources SlurmResources::overridden_by(const SlurmResources& over) const {
  SlurmResources r = *this;
  if (!over.partition.empty()) r.partition = over.partition;
  if (!over.time.empty()) r.time = over.time;
  if (over.cpus > 0) r.cpus = over.cpus;
  if (!over.mem.empty()) r.mem = over.mem;
  return r;
}

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
    if (!names.insert(e.name).second)
      throw InputError(fmt::format("{}: experiment name '{}' used twice", f.string(), e.name));
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
    if (std::none_of(picked.begin(), picked.end(), [&](const auto& p) { return p.name == want; }))
      picked.push_back(*it);
  }
  return picked;
}

}  // namespace meltlab::experiments
