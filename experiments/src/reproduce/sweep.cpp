// meltlab sweep (meltlab/experiments/sweep.h): a sweep config turned into an experiment of the
// reproduce engine, and the collection of its measures into sweep.csv.
#include "stages.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/config.h>
#include <meltlab/core/error.h>
#include <meltlab/core/input_file.h>
#include <meltlab/experiments/sweep.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <charconv>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

namespace meltlab::experiments {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

/// The most points one sweep may have (each is a run folder and a Slurm array task).
constexpr std::size_t kMaxPoints = 10000;

bool is_number(const std::string& s) {
  double v = 0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return !s.empty() && r.ec == std::errc() && r.ptr == s.data() + s.size();
}

/// An option name: --name (what every meltlab option looks like).
void check_option(const std::string& option, const ConfigSection& where, const std::string& key) {
  static const std::regex re("--[a-z][a-z0-9-]*");
  if (!std::regex_match(option, re)) where.fail_at(key, fmt::format("'{}' is not an option (--name)", option));
  if (option == "--out") where.fail_at(key, "--out is the point's folder, set by the sweep");
}

/// A CSV cell: quoted when it holds a comma, a quote or a line break.
std::string csv_cell(const std::string& v) {
  if (v.find_first_of(",\"\n\r") == std::string::npos) return v;
  std::string q = "\"";
  for (const char c : v) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// Splits one CSV line (RFC 4180 quotes).
std::vector<std::string> csv_split(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else if (c != '\r') {
      out.back() += c;
    }
  }
  return out;
}

std::string measure_value(const SweepMeasure& m, const fs::path& point_dir) {
  const fs::path file = point_dir / m.file;
  const std::string text = read_text_file(file, "sweep measure");
  if (!m.json.empty()) {
    json j;
    try {
      j = json::parse(text);
    } catch (const json::parse_error& e) {
      throw InputError(fmt::format("{}: not JSON ({})", file.string(), e.what()));
    }
    const json* at = &j;
    std::stringstream keys(m.json);
    for (std::string key; std::getline(keys, key, '.');) {
      if (at->is_array() && is_number(key) && std::stoul(key) < at->size())
        at = &(*at)[std::stoul(key)];
      else if (at->is_object() && at->contains(key))
        at = &(*at)[key];
      else
        throw InputError(fmt::format("{}: no '{}' (measure '{}')", file.string(), m.json, m.name));
    }
    if (at->is_string()) return at->get<std::string>();
    if (at->is_structured())
      throw InputError(fmt::format("{}: '{}' is not a number or a text (measure '{}')", file.string(), m.json, m.name));
    return at->dump();
  }
  std::istringstream in(text);
  std::string header_line, line, last;
  std::getline(in, header_line);
  while (std::getline(in, line))
    if (!line.empty() && line != "\r") last = line;
  const auto header = csv_split(header_line);
  const auto it = std::find(header.begin(), header.end(), m.column);
  if (it == header.end())
    throw InputError(fmt::format("{}:1: no column '{}' (measure '{}')", file.string(), m.column, m.name));
  if (last.empty()) throw InputError(fmt::format("{}: no rows (measure '{}')", file.string(), m.name));
  const auto cells = csv_split(last);
  const auto col = static_cast<std::size_t>(it - header.begin());
  return col < cells.size() ? cells[col] : std::string();
}

}  // namespace

Sweep load_sweep(const fs::path& file) {
  Sweep s;
  s.file = file;
  s.text = read_text_file(file, "sweep config");
  const ConfigSection root(parse_yaml_text(s.text, file.string()), file.string());
  s.name = root.require<std::string>("name");
  static const std::regex name_re("[a-z0-9_]+");
  if (!std::regex_match(s.name, name_re) || s.name == "report" || s.name == "logs")
    root.fail_at("name", fmt::format("name '{}' must be [a-z0-9_]+ and not 'report' or 'logs'", s.name));
  s.title = root.get<std::string>("title", s.name);
  root.ignore("notes");
  s.command = root.require<std::string>("command");
  static const std::regex command_re("[a-z][a-z-]*");
  if (!std::regex_match(s.command, command_re) || s.command == "sweep" || s.command == "reproduce" ||
      s.command == "run-job")
    root.fail_at("command", fmt::format("'{}' is not a subcommand a sweep can run", s.command));
  if (const auto args = root.optional_value("args")) {
    if (!args->is_sequence()) args->fail("must be a list");
    for (const ConfigValue& a : args->items()) {
      s.args.push_back(a.as<std::string>());
      if (s.args.back() == "--out") a.fail("--out is the point's folder, set by the sweep");
    }
  }

  // The points: the grid's combinations, then the listed ones; each sets the same options.
  std::vector<std::vector<std::pair<std::string, std::string>>> points;
  auto value_text = [](const ConfigValue& v) {
    if (!v.is_scalar()) v.fail("must be a single value (a number, a text, true or false)");
    return v.as<std::string>();
  };
  if (const auto grid = root.optional_section("grid")) {
    std::vector<std::pair<std::string, std::vector<std::string>>> axes;
    for (const std::string& option : grid->keys()) {
      check_option(option, *grid, option);
      const ConfigValue values = grid->value(option);
      if (!values.is_sequence() || values.items().empty()) values.fail("must be a non-empty list of values");
      std::vector<std::string> texts;
      for (const ConfigValue& v : values.items()) texts.push_back(value_text(v));
      axes.emplace_back(option, texts);
    }
    std::size_t n = axes.empty() ? 0 : 1;
    for (const auto& [_, v] : axes) {
      n *= v.size();
      if (n > kMaxPoints) grid->fail(fmt::format("more than {} points", kMaxPoints));
    }
    for (std::size_t i = 0; i < n; ++i) {
      std::vector<std::pair<std::string, std::string>> p;
      std::size_t rest = i, stride = n;
      for (const auto& [option, values] : axes) {  // the first option varies slowest
        stride /= values.size();
        p.emplace_back(option, values[rest / stride]);
        rest %= stride;
      }
      points.push_back(std::move(p));
    }
  }
  if (const auto listed = root.optional_value("points")) {
    if (!listed->is_sequence()) listed->fail("must be a list of maps (option: value)");
    for (const ConfigValue& item : listed->items()) {
      if (!item.is_map()) item.fail("must be a map (option: value)");
      const ConfigSection ps = item.section();
      std::vector<std::pair<std::string, std::string>> p;
      for (const std::string& option : ps.keys()) {
        check_option(option, ps, option);
        p.emplace_back(option, value_text(ps.value(option)));
      }
      points.push_back(std::move(p));
      if (points.size() > kMaxPoints) item.fail(fmt::format("more than {} points", kMaxPoints));
    }
  }
  if (points.empty()) root.fail("needs 'grid' or 'points' (at least one point)");
  for (const auto& [option, _] : points.front()) s.options.push_back(option);
  std::set<std::string> option_set(s.options.begin(), s.options.end());
  if (option_set.size() != s.options.size()) root.fail("an option is given twice in a point");
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::set<std::string> here;
    for (const auto& [option, _] : points[i]) here.insert(option);
    if (here != option_set)
      root.fail(fmt::format("point {} sets other options than point 0 (every point sets the same options)", i));
    std::vector<std::pair<std::string, std::string>> ordered;
    for (const auto& option : s.options)
      for (const auto& kv : points[i])
        if (kv.first == option) ordered.push_back(kv);
    for (const auto& a : s.args)
      if (option_set.count(a)) root.fail(fmt::format("option {} is both swept and in 'args'", a));
    const int digits = std::max(3, static_cast<int>(std::to_string(points.size() - 1).size()));
    s.points.push_back({fmt::format("p{:0{}}", i, digits), ordered});
  }

  if (!root.has("measures")) root.fail("missing key 'measures' (a non-empty list)");
  std::set<std::string> measure_names;
  for (const ConfigSection& m : root.sections("measures")) {
    SweepMeasure x;
    x.name = m.require<std::string>("name");
    if (!std::regex_match(x.name, name_re) || !measure_names.insert(x.name).second)
      m.fail_at("name", fmt::format("measure name '{}' must be [a-z0-9_]+ and unique", x.name));
    x.file = m.require<std::string>("file");
    if (x.file.empty() || fs::path(x.file).is_absolute() || x.file.find("..") != std::string::npos)
      m.fail_at("file", fmt::format("'{}' must be a file inside the point's folder", x.file));
    if (m.has("json") == m.has("column")) m.fail("a measure needs exactly one of 'json' and 'column'");
    x.json = m.get<std::string>("json", "");
    x.column = m.get<std::string>("column", "");
    s.measures.push_back(x);
  }
  if (s.measures.empty()) root.fail_at("measures", "'measures' must be a non-empty list");
  for (const auto& option : s.options) {
    if (std::all_of(s.points.begin(), s.points.end(), [&](const SweepPoint& p) {
          for (const auto& [o, v] : p.values)
            if (o == option) return is_number(v);
          return false;
        })) {
      s.x = option;
      break;
    }
  }
  if (const auto x = root.optional<std::string>("x")) {
    if (!option_set.count(*x)) root.fail_at("x", fmt::format("'{}' is not a swept option", *x));
    s.x = *x;
  }
  if (const auto slurm = root.optional_section("slurm")) s.slurm = reproduce_detail::slurm_section(*slurm);
  root.finish();
  return s;
}

ReproduceExperiment sweep_experiment(const Sweep& s, const ReproduceOptions& o) {
  ReproduceExperiment e;
  e.name = s.name;
  e.title = s.title;
  e.sources = {"sweep"};
  e.config_file = s.file;
  e.out_dir = o.out_dir / s.name;
  reproduce_detail::add_sweep_steps(s, o, e);
  reproduce_detail::find_waves(e);
  e.hash = reproduce_detail::content_hash(e, s.text, "sweep");
  return e;
}

namespace reproduce_detail {

void add_sweep_steps(const Sweep& s, const ReproduceOptions& o, ReproduceExperiment& e) {
  for (const auto& p : s.points) {
    ReproduceStep step;
    step.name = p.name;
    step.kind = "meltlab";
    step.args = {s.command};
    step.args.insert(step.args.end(), s.args.begin(), s.args.end());
    for (const auto& [option, value] : p.values) {
      if (value == "false") continue;
      step.args.push_back(option);
      if (value != "true") step.args.push_back(value);
    }
    step.args.push_back("--out");
    step.args.push_back((e.out_dir / p.name).string());
    step.slurm = s.slurm;
    e.steps.push_back(step);
  }
  ReproduceStep collect;
  collect.name = "collect";
  collect.kind = "meltlab";
  collect.args = {"sweep", "--config", s.file.string(), "--collect", e.out_dir.string()};
  e.steps.push_back(collect);
  ReproduceStep figures;
  figures.name = "figures";
  figures.kind = "python";
  figures.args = {(o.source_dir / "report" / "experiment_report.py").string(), "sweep", e.out_dir.string()};
  e.steps.push_back(figures);
  // Inputs: the config, the report scripts, and the files the arguments name (a mesh, a kl field).
  e.hashed_files.push_back(s.file);
  std::error_code ec;
  std::size_t modules = 0;
  for (fs::recursive_directory_iterator it(o.source_dir / "report", ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec) && it->path().extension() == ".py") {
      e.hashed_files.push_back(it->path());
      ++modules;
    }
  std::sort(e.hashed_files.end() - static_cast<std::ptrdiff_t>(modules), e.hashed_files.end());
  std::set<fs::path> named;
  for (const auto& step : e.steps)
    for (const auto& a : step.args) {
      const fs::path p(a);
      if (p.is_absolute() && fs::is_regular_file(p, ec) && p != s.file && !named.count(p)) {
        const auto rel = fs::relative(p, o.out_dir, ec);
        if (!ec && !rel.empty() && rel.begin()->string() != "..") continue;
        named.insert(p);
        e.hashed_files.push_back(p);
      }
    }
}

}  // namespace reproduce_detail

void collect_sweep(const Sweep& s, const fs::path& dir) {
  std::string csv = "point";
  for (const auto& option : s.options) csv += "," + csv_cell(option);
  for (const auto& m : s.measures) csv += "," + csv_cell(m.name);
  csv += "\n";
  for (const auto& p : s.points) {
    csv += p.name;
    for (const auto& [_, v] : p.values) csv += "," + csv_cell(v);
    for (const auto& m : s.measures) csv += "," + csv_cell(measure_value(m, dir / p.name));
    csv += "\n";
  }
  json measures = json::array();
  for (const auto& m : s.measures)
    measures.push_back({{"name", m.name}, {"file", m.file}, {"key", m.json.empty() ? m.column : m.json}});
  const json meta = {{"name", s.name}, {"title", s.title},         {"command", s.command},
                     {"args", s.args}, {"options", s.options},     {"measures", measures},
                     {"x", s.x},       {"points", s.points.size()}};
  write_text_atomically(dir / "sweep.csv", csv);
  write_text_atomically(dir / "sweep.json", meta.dump(2) + "\n");
}

}  // namespace meltlab::experiments
