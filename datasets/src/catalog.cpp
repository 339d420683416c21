// Reading datasets/catalog.yaml (catalog.h) and the folders datasets live in.

#include <meltlab/core/yaml_keys.h>
#include <meltlab/core/input_file.h>
#include <meltlab/datasets/catalog.h>
#include <meltlab/datasets/molds.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

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

// Where a YAML node sits, for messages: "line 12".
std::string where(const YAML::Node& node) { return fmt::format("line {}", node.Mark().line + 1); }

DatasetKind kind_from_name(const std::string& s, const std::string& context) {
  if (s == "cgal") return DatasetKind::kCgal;
  if (s == "procedural") return DatasetKind::kProcedural;
  if (s == "mold") return DatasetKind::kMold;
  if (s == "refined") return DatasetKind::kRefined;
  throw InputError(fmt::format("{}: kind '{}' is not one of cgal, procedural, mold, refined", context, s));
}

template <class T>
T scalar_as(const YAML::Node& node, const std::string& context, const char* key) {
  if (!node.IsScalar()) throw InputError(fmt::format("{}: '{}' must be a single value", context, key));
  try {
    return node.as<T>();
  } catch (const YAML::Exception&) {
    throw InputError(fmt::format("{}: '{}' has a bad value '{}'", context, key, node.Scalar()));
  }
}

DatasetEntry parse_entry(const YAML::Node& node, const std::string& file) {
  if (!node.IsMap()) throw InputError(fmt::format("{}: {}: each dataset must be a map of keys", file, where(node)));
  static const std::set<std::string> kKnown = {"name",        "kind",      "source",          "params",
                                               "description", "triangles", "closed_manifold", "need_repair",
                                               "problem",     "genus",     "shells"};
  const std::string name_context = fmt::format("{}: {}", file, where(node));
  if (!node["name"]) throw InputError(fmt::format("{}: dataset without a 'name'", name_context));
  DatasetEntry e;
  e.name = scalar_as<std::string>(node["name"], name_context, "name");
  const std::string context = fmt::format("{}: dataset '{}' ({})", file, e.name, where(node));
  for (const auto& kv : node) {
    const auto key = kv.first.as<std::string>();
    if (!kKnown.count(key)) throw InputError(fmt::format("{}: unknown key '{}'", context, key));
  }
  for (const char* required : {"kind", "source", "description", "triangles"})
    if (!node[required]) throw InputError(fmt::format("{}: missing key '{}'", context, required));
  e.kind = kind_from_name(scalar_as<std::string>(node["kind"], context, "kind"), context);
  e.source = scalar_as<std::string>(node["source"], context, "source");
  e.description = scalar_as<std::string>(node["description"], context, "description");
  e.triangles = scalar_as<std::int64_t>(node["triangles"], context, "triangles");
  if (e.triangles <= 0) throw InputError(fmt::format("{}: 'triangles' must be positive", context));
  if (node["params"]) {
    if (e.kind == DatasetKind::kCgal)
      throw InputError(fmt::format("{}: only procedural, mold and refined datasets take 'params'", context));
    if (!node["params"].IsMap()) throw InputError(fmt::format("{}: 'params' must be a map", context));
    for (const auto& kv : node["params"])
      e.params[kv.first.as<std::string>()] = scalar_as<std::string>(kv.second, context, "params");
  }
  if (e.kind == DatasetKind::kCgal) {
    if (!node["closed_manifold"])
      throw InputError(fmt::format("{}: a cgal dataset must say whether it is a closed manifold", context));
    e.closed_manifold = scalar_as<bool>(node["closed_manifold"], context, "closed_manifold");
  } else if (node["closed_manifold"] && !scalar_as<bool>(node["closed_manifold"], context, "closed_manifold")) {
    throw InputError(fmt::format("{}: generated datasets are always closed manifolds", context));
  }
  e.need_repair =
      node["need_repair"] ? scalar_as<bool>(node["need_repair"], context, "need_repair") : !e.closed_manifold;
  if (!e.closed_manifold && !e.need_repair)
    throw InputError(fmt::format("{}: a dataset that is not a closed manifold needs need_repair: true", context));
  if (node["problem"]) e.problem = scalar_as<std::string>(node["problem"], context, "problem");
  if (e.need_repair && e.problem.empty())
    throw InputError(fmt::format("{}: need_repair datasets must say what the 'problem' is", context));
  if (node["genus"]) e.genus = scalar_as<int>(node["genus"], context, "genus");
  if (node["shells"]) e.shells = scalar_as<int>(node["shells"], context, "shells");
  if (e.genus < 0 || e.shells < 1) throw InputError(fmt::format("{}: genus must be >= 0 and shells >= 1", context));
  switch (e.kind) {
    case DatasetKind::kCgal:
      if (e.source.empty() || e.source.front() == '/' || e.source.find("..") != std::string::npos)
        throw InputError(fmt::format("{}: source must be a relative archive member path", context));
      break;
    case DatasetKind::kProcedural:
      if (!detail::is_known_generator(e.source))
        throw InputError(fmt::format("{}: unknown generator '{}'", context, e.source));
      break;
    case DatasetKind::kMold:
      try {
        (void)mold_from_name(e.source);
      } catch (const InputError& err) {
        throw InputError(fmt::format("{}: {}", context, err.what()));
      }
      break;
    case DatasetKind::kRefined:
      break;  // the source must name another dataset: checked once the whole list is read
  }
  return e;
}

}  // namespace

namespace detail {

CatalogFile read_catalog_checked(const fs::path& yaml_file);

CatalogFile read_catalog(const fs::path& yaml_file) {
  try {
    return read_catalog_checked(yaml_file);
  } catch (const YAML::Exception& e) {
    throw yaml_error(yaml_file.string(), e, "bad value");
  }
}

CatalogFile read_catalog_checked(const fs::path& yaml_file) {
  const std::string file = yaml_file.string();
  std::error_code ec;
  if (!fs::is_regular_file(yaml_file, ec))
    throw InputError(
        fmt::format("{}: dataset catalog not found (set MELTLAB_DATASETS_DIR to the folder holding "
                    "catalog.yaml)",
                    file));
  const std::string text = read_text_file(file, "dataset catalog");
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw yaml_error(file, e);
  }
  if (!root.IsMap()) throw InputError(fmt::format("{}: the catalog must be a map with 'archive' and 'datasets'", file));
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (key != "archive" && key != "datasets")
      throw InputError(fmt::format("{}: {}: unknown top-level key '{}'", file, where(kv.first), key));
  }
  CatalogFile out;
  if (!root["archive"] || !root["archive"].IsScalar())
    throw InputError(fmt::format("{}: missing 'archive' (path of CGAL's data.tar.gz)", file));
  out.archive = root["archive"].as<std::string>();
  const YAML::Node list = root["datasets"];
  if (!list || !list.IsSequence() || list.size() == 0)
    throw InputError(fmt::format("{}: 'datasets' must be a non-empty list", file));
  std::set<std::string> names;
  for (const auto& node : list) {
    DatasetEntry e = parse_entry(node, file);
    if (!names.insert(e.name).second)
      throw InputError(fmt::format("{}: {}: dataset name '{}' is used twice", file, where(node), e.name));
    out.entries.push_back(std::move(e));
  }
  for (const DatasetEntry& e : out.entries) {
    if (e.kind != DatasetKind::kRefined) continue;
    const auto src = std::find_if(out.entries.begin(), out.entries.end(),
                                  [&](const DatasetEntry& s) { return s.name == e.source; });
    if (src == out.entries.end())
      throw InputError(fmt::format("{}: refined dataset '{}': source '{}' is not a dataset of the catalog", file, e.name,
                                   e.source));
    if (src->kind == DatasetKind::kRefined)
      throw InputError(fmt::format("{}: refined dataset '{}': source '{}' is itself refined", file, e.name, e.source));
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
