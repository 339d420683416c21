// meltlab mesh-info: validity and quality figures of a mesh as JSON (monograph §2.3–2.4).

#include <meltlab/experiments/simulate_run.h>
#include <meltlab/sim/cgal/self_intersection.h>
#include <meltlab/sim/mesh_io.h>
#include <meltlab/sim/quality.h>
#include <meltlab/sim/topology.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdio>

#include "cli_util.h"
#include "commands.h"

namespace meltlab::cli {

namespace {
nlohmann::json counts_json(const sim::EulerCounts& c) {
  return {{"V", c.V}, {"E", c.E}, {"F", c.F},     {"H", c.H},
          {"S", c.S}, {"G", c.G}, {"chi", c.chi}, {"consistent", c.genus_valid}};
}
}  // namespace

Run add_mesh_info(CLI::App& app) {
  auto* sub = app.add_subcommand(
      "mesh-info",
      "Print a mesh's Euler counts (Eq. 2.3), validity and quality measures (Eq. 2.4-2.8) as JSON; exit 1 if invalid");
  auto mesh = std::make_shared<std::string>();
  auto options = std::make_shared<sim::LoadOptions>();
  sub->add_option("mesh", *mesh, "Mesh file or dataset name")->required();
  sub->add_option("--weld-tol", options->weld_tolerance, "Merge vertices closer than this (mesh units)")
      ->default_val(0.0);
  sub->add_flag("--repair", options->repair, "Report the mesh after CGAL repair");
  auto intersections = std::make_shared<bool>(false);
  sub->add_flag("--self-intersections", *intersections,
                "Also test for self-intersections with CGAL (exact predicates)");
  return [=]() {
    const auto path = experiments::resolve_mesh_argument(*mesh);
    sim::LoadOptions opt = *options;
    opt.validate = opt.repair;  // without --repair, load invalid meshes too so they can be reported
    const sim::LoadedMesh loaded = sim::load_mesh(path, opt);
    const auto tm = sim::TriMesh<double>::from_indexed(loaded.mesh);
    const sim::TopologyReport topo = sim::check_topology(tm, 20);
    const sim::QualityReport q = sim::mesh_quality(tm);
    nlohmann::json problems = nlohmann::json::array();
    for (const auto& p : topo.problems) problems.push_back(p.describe());
    // A closed, manifold, consistently oriented mesh whose faces point inwards is no solid
    // either: `simulate` refuses it (load_mesh), so mesh-info calls it invalid too.
    const bool inside_out = topo.valid() && q.volume < 0.0;
    if (inside_out)
      problems.push_back(fmt::format("inside-out: the faces are oriented inwards (volume {:.6g} < 0)", q.volume));
    const bool valid = topo.valid() && !inside_out;
    const auto& r = loaded.report;
    nlohmann::json out = {
        {"file", path.string()},
        {"format", sim::mesh_format_of(path)},
        {"load",
         {{"file_vertices", r.file_vertices},
          {"file_faces", r.file_faces},
          {"welded_vertices", r.welded_vertices},
          {"unreferenced_vertices", r.unreferenced_vertices},
          {"degenerate_faces", r.degenerate_faces},
          {"repairs", r.repairs}}},
        {"polygons", counts_json(r.file_counts)},
        {"triangles", counts_json(topo.counts)},
        {"valid", valid},
        {"inside_out", inside_out},
        {"closed", topo.closed},
        {"manifold", topo.manifold},
        {"oriented", topo.oriented},
        {"problem_counts",
         {{"boundary_edges", topo.boundary_edges},
          {"nonmanifold_edges", topo.nonmanifold_edges},
          {"nonmanifold_vertices", topo.nonmanifold_vertices},
          {"misoriented_edges", topo.misoriented_edges},
          {"low_valence_vertices", topo.low_valence_vertices}}},
        {"problems", problems},
        {"quality",
         {{"Qs_deg", q.Qs},
          {"Qd_deg", q.Qd},
          {"Qq", q.Qq},
          {"max_d_deg", q.max_d},
          {"min_q", q.min_q},
          {"volume", q.volume},
          {"area", q.area},
          {"mean_edge_length", q.mean_edge_length},
          {"bbox_min", {q.bbox_min.x(), q.bbox_min.y(), q.bbox_min.z()}},
          {"bbox_max", {q.bbox_max.x(), q.bbox_max.y(), q.bbox_max.z()}}}},
    };
    bool intersects = false;
    if (*intersections) {
      const sim::SelfIntersectionReport si = sim::self_intersections(tm, 1000);
      intersects = si.intersects;
      nlohmann::json sample = nlohmann::json::array();
      for (std::size_t k = 0; k < std::min<std::size_t>(si.sample.size(), 10); ++k)
        sample.push_back({si.sample[k].first, si.sample[k].second});
      out["self_intersections"] = {{"intersects", si.intersects},
                                   {"pairs", si.pairs},
                                   {"first_pairs", sample},
                                   {"note", "pairs capped at 1000; triangles are indices into the loaded mesh"}};
    }
    std::printf("%s\n", out.dump(2).c_str());
    return static_cast<int>(valid && !intersects ? kExitOk : kExitInvalid);
  };
}

}  // namespace meltlab::cli
