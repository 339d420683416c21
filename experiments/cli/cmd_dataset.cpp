// meltlab dataset: the catalog of input meshes (libcgal-demo meshes, procedural shapes, molds).

#include <meltlab/datasets/catalog.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>

#include "cli_util.h"
#include "commands.h"

namespace meltlab::cli {

Run add_dataset(CLI::App& app) {
  auto* sub = app.add_subcommand("dataset", "List the dataset catalog, or extract/generate datasets into the cache");
  sub->require_subcommand(1);
  auto* list = sub->add_subcommand("list", "List every dataset with its kind, size and description");
  auto as_json = std::make_shared<bool>(false);
  list->add_flag("--json", *as_json, "Print the catalog as JSON");
  auto* get = sub->add_subcommand("get", "Extract or generate datasets into the cache and print their paths");
  auto names = std::make_shared<std::vector<std::string>>();
  get->add_option("names", *names, "Dataset names (or 'all')")->required();
  return [=]() {
    if (list->parsed()) {
      const auto catalog = datasets::dataset_catalog();
      if (*as_json) {
        nlohmann::json out = nlohmann::json::array();
        for (const auto& e : catalog)
          out.push_back({{"name", e.name}, {"kind", datasets::dataset_kind_name(e.kind)}, {"source", e.source},
                         {"triangles", e.triangles}, {"closed_manifold", e.closed_manifold}, {"need_repair", e.need_repair},
                         {"genus", e.genus}, {"shells", e.shells}, {"description", e.description}});
        std::printf("%s\n", out.dump(2).c_str());
      } else {
        std::printf("%-24s %-10s %10s  %s\n", "name", "kind", "triangles", "description");
        for (const auto& e : catalog)
          std::printf("%-24s %-10s %10lld  %s%s\n", e.name.c_str(), datasets::dataset_kind_name(e.kind).c_str(),
                      static_cast<long long>(e.triangles), e.description.c_str(), e.need_repair ? " [needs --repair]" : "");
        std::printf("cache: %s\n", datasets::default_cache_dir().string().c_str());
      }
      return static_cast<int>(kOk);
    }
    std::vector<std::string> wanted = *names;
    if (wanted.size() == 1 && wanted[0] == "all") {
      wanted.clear();
      for (const auto& e : datasets::dataset_catalog()) wanted.push_back(e.name);
    }
    for (const auto& n : wanted) std::printf("%s\n", datasets::dataset_path(n).string().c_str());
    return static_cast<int>(kOk);
  };
}

}  // namespace meltlab::cli
