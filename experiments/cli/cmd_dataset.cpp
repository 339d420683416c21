// meltlab dataset: the catalog of input meshes (libcgal-demo meshes, procedural shapes, molds).

#include <meltlab/datasets/catalog.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/polygon_mesh.h>
#include <meltlab/sim/topology.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <functional>
#include <map>

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
  // Tab. 2.3's polyhedra in their polygon form (faces with hole loops), which no mesh file
  // format keeps: the catalog stores them triangulated, so their file counts differ.
  auto* euler = sub->add_subcommand(
      "euler", "Eq. 2.3 counts (V E F H S G chi) of the Tab. 2.3 polyhedra in polygon form, as JSON");
  auto shapes = std::make_shared<std::vector<std::string>>();
  euler->add_option("names", *shapes,
                    "cube_quads, cube_triangles, double_cube_quads, cube_with_face_hole, cube_with_tunnel, "
                    "cube_with_tunnel_front_triangulated (default: all)");
  return [=]() {
    if (euler->parsed()) {
      const std::map<std::string, std::function<sim::PolygonMesh()>> polygon_forms{
          {"cube_quads", [] { return datasets::cube_quads(); }},
          {"cube_triangles", [] { return sim::to_polygon_mesh(datasets::cube_triangles()); }},
          {"double_cube_quads", [] { return datasets::double_cube_quads(); }},
          {"cube_with_face_hole", [] { return datasets::cube_with_face_hole(); }},
          {"cube_with_tunnel", [] { return datasets::cube_with_tunnel(); }},
          {"cube_with_tunnel_front_triangulated", [] { return datasets::cube_with_tunnel_front_triangulated(); }}};
      std::vector<std::string> wanted = *shapes;
      if (wanted.empty())
        for (const auto& [n, make] : polygon_forms) wanted.push_back(n);
      nlohmann::json out = nlohmann::json::object();
      for (const auto& n : wanted) {
        const auto it = polygon_forms.find(n);
        if (it == polygon_forms.end())
          throw InputError(fmt::format("dataset euler: '{}' is not one of the Tab. 2.3 polyhedra", n));
        const sim::EulerCounts c = sim::euler_counts(it->second());
        out[n] = {{"V", c.V}, {"E", c.E}, {"F", c.F},     {"H", c.H},
                  {"S", c.S}, {"G", c.G}, {"chi", c.chi}, {"consistent", c.genus_valid}};
      }
      std::printf("%s\n", out.dump(2).c_str());
      return kExitOk;
    }
    if (list->parsed()) {
      const auto catalog = datasets::dataset_catalog();
      if (*as_json) {
        nlohmann::json out = nlohmann::json::array();
        for (const auto& e : catalog)
          out.push_back({{"name", e.name},
                         {"kind", datasets::dataset_kind_name(e.kind)},
                         {"source", e.source},
                         {"triangles", e.triangles},
                         {"closed_manifold", e.closed_manifold},
                         {"need_repair", e.need_repair},
                         {"genus", e.genus},
                         {"shells", e.shells},
                         {"description", e.description}});
        std::printf("%s\n", out.dump(2).c_str());
      } else {
        std::printf("%-24s %-10s %10s  %s\n", "name", "kind", "triangles", "description");
        for (const auto& e : catalog)
          std::printf("%-24s %-10s %10lld  %s%s\n", e.name.c_str(), datasets::dataset_kind_name(e.kind).c_str(),
                      static_cast<long long>(e.triangles), e.description.c_str(),
                      e.need_repair ? " [needs --repair]" : "");
        std::printf("cache: %s\n", datasets::default_cache_dir().string().c_str());
      }
      return kExitOk;
    }
    std::vector<std::string> wanted = *names;
    if (wanted.size() == 1 && wanted[0] == "all") {
      wanted.clear();
      for (const auto& e : datasets::dataset_catalog()) wanted.push_back(e.name);
    }
    for (const auto& n : wanted) std::printf("%s\n", datasets::dataset_path(n).string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
