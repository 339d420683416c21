// Reading datasets/catalog.yaml (catalog.h) and the folders datasets live in.

#include <meltlab/core/config.h>
#include <meltlab/datasets/catalog.h>
#include <meltlab/datasets/molds.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <set>

#include "catalog_internal.h"

#ifndef MELTLAB_DATASETS_DIR
#error "MELTLAB_DATASETS_DIR must be defined by the build (datasets/CMakeLists.txt)"
#endif

namespace meltlab::datasets {

namespace fs = std::filesystem;

namespace {

std::string env_or_empty(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::string(v) : std::string();
}

DatasetKind kind_of(const ConfigSection& d) {
  const std::string s = d.require<std::string>("kind");
  if (s == "cgal") return DatasetKind::kCgal;
  if (s == "procedural") return DatasetKind::kProcedural;
  if (s == "mold") return DatasetKind::kMold;
  if (s == "refined") return DatasetKind::kRefined;
  d.fail_at("kind", fmt::format("kind '{}' is not one of cgal, procedural, mold, refined", s));
}

DatasetEntry parse_entry(const ConfigSection& d) {
  DatasetEntry e;
  e.name = d.require<std::string>("name");
  // Problems of the entry as a whole, at its line: "dataset 'bunny00': ...".
  const auto fail = [&](const std::string& key, const std::string& problem) {
    d.fail_at(key, fmt::format("dataset '{}': {}", e.name, problem));
  };
  e.kind = kind_of(d);
  e.source = d.require<std::string>("source");
  e.description = d.require<std::string>("description");
  e.triangles = d.require<std::int64_t>("triangles");
  if (e.triangles <= 0) fail("triangles", "'triangles' must be positive");
  if (const auto params = d.optional_section("params")) {
    if (e.kind == DatasetKind::kCgal) fail("params", "only procedural, mold and refined datasets take 'params'");
    for (const std::string& key : params->keys()) e.params[key] = params->require<std::string>(key);
  }
  if (e.kind == DatasetKind::kCgal) {
    if (!d.has("closed_manifold"))
      d.fail(fmt::format("dataset '{}': a cgal dataset must say whether it is a closed manifold", e.name));
    e.closed_manifold = d.require<bool>("closed_manifold");
  } else if (!d.get("closed_manifold", true)) {
    fail("closed_manifold", "generated datasets are always closed manifolds");
  }
  e.need_repair = d.get("need_repair", !e.closed_manifold);
  if (!e.closed_manifold && !e.need_repair)
    fail("need_repair", "a dataset that is not a closed manifold needs need_repair: true");
  e.problem = d.get<std::string>("problem", "");
  if (e.need_repair && e.problem.empty()) fail("problem", "need_repair datasets must say what the 'problem' is");
  e.genus = d.get("genus", e.genus);
  e.shells = d.get("shells", e.shells);
  if (e.genus < 0 || e.shells < 1) fail("genus", "genus must be >= 0 and shells >= 1");
  switch (e.kind) {
    case DatasetKind::kCgal:
      if (e.source.empty() || e.source.front() == '/' || e.source.find("..") != std::string::npos)
        fail("source", "source must be a relative archive member path");
      break;
    case DatasetKind::kProcedural:
      if (!detail::is_known_generator(e.source)) fail("source", fmt::format("unknown generator '{}'", e.source));
      break;
    case DatasetKind::kMold:
      try {
        (void)mold_from_name(e.source);
      } catch (const InputError& err) {
        fail("source", err.what());
      }
      break;
    case DatasetKind::kRefined:
      break;  // the source must name another dataset: checked once the whole list is read
  }
  return e;
}

}  // namespace

namespace detail {

CatalogFile read_catalog(const fs::path& yaml_file) {
  const std::string file = yaml_file.string();
  std::error_code ec;
  if (!fs::is_regular_file(yaml_file, ec))
    throw InputError(
        fmt::format("{}: dataset catalog not found (set MELTLAB_DATASETS_DIR to the folder holding "
                    "catalog.yaml)",
                    file));
  const ConfigSection root = load_config(yaml_file, "dataset catalog");
  CatalogFile out;
  if (!root.has("archive")) root.fail("missing key 'archive' (path of CGAL's data.tar.gz)");
  out.archive = root.require<std::string>("archive");
  const std::vector<ConfigSection> list =
      root.has("datasets") ? root.sections("datasets") : std::vector<ConfigSection>{};
  if (list.empty()) root.fail_at("datasets", "'datasets' must be a non-empty list");
  std::set<std::string> names;
  for (const ConfigSection& d : list) {
    DatasetEntry e = parse_entry(d);
    if (!names.insert(e.name).second) d.fail_at("name", fmt::format("dataset name '{}' is used twice", e.name));
    out.entries.push_back(std::move(e));
  }
  root.finish();
  for (std::size_t i = 0; i < out.entries.size(); ++i) {
    const DatasetEntry& e = out.entries[i];
    if (e.kind != DatasetKind::kRefined) continue;
    const auto src =
        std::find_if(out.entries.begin(), out.entries.end(), [&](const DatasetEntry& s) { return s.name == e.source; });
    if (src == out.entries.end())
      list[i].fail_at(
          "source", fmt::format("refined dataset '{}': source '{}' is not a dataset of the catalog", e.name, e.source));
    if (src->kind == DatasetKind::kRefined)
      list[i].fail_at("source", fmt::format("refined dataset '{}': source '{}' is itself refined", e.name, e.source));
  }
  return out;
}

}  // namespace detail

std::string dataset_kind_name(DatasetKind kind) {
  switch (kind) {
    case DatasetKind::kCgal:
      return "cgal";
    case DatasetKind::kProcedural:
      return "procedural";
    case DatasetKind::kMold:
      return "mold";
    case DatasetKind::kRefined:
      return "refined";
  }
  return "unknown";
}

fs::path datasets_dir() {
  const std::string env = env_or_empty("MELTLAB_DATASETS_DIR");
  return env.empty() ? fs::path(MELTLAB_DATASETS_DIR) : fs::path(env);
}

std::vector<DatasetEntry> dataset_catalog() { return dataset_catalog(datasets_dir() / "catalog.yaml"); }

std::vector<DatasetEntry> dataset_catalog(const fs::path& yaml_file) { return detail::read_catalog(yaml_file).entries; }

DatasetEntry dataset_entry(const std::string& name) {
  const fs::path file = datasets_dir() / "catalog.yaml";
  for (auto& e : dataset_catalog(file))
    if (e.name == name) return e;
  throw InputError(fmt::format("unknown dataset '{}' (not in {})", name, file.string()));
}

fs::path cgal_data_archive() {
  const std::string env = env_or_empty("MELTLAB_CGAL_DATA_ARCHIVE");
  if (!env.empty()) return env;
  return detail::read_catalog(datasets_dir() / "catalog.yaml").archive;
}

fs::path default_cache_dir() {
  if (std::string d = env_or_empty("MELTLAB_DATA_DIR"); !d.empty()) return d;
  if (std::string x = env_or_empty("XDG_CACHE_HOME"); !x.empty()) return fs::path(x) / "meltlab";
  if (std::string h = env_or_empty("HOME"); !h.empty()) return fs::path(h) / ".cache" / "meltlab";
  throw InputError("dataset cache: none of MELTLAB_DATA_DIR, XDG_CACHE_HOME, HOME is set; set MELTLAB_DATA_DIR");
}

}  // namespace meltlab::datasets
