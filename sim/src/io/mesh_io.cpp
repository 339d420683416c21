// Mesh files: read by our own readers (mesh_readers.h says why not OpenMesh's), written through
// OpenMesh's IO layer.

#include "mesh_readers.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>
#include <meltlab/sim/cgal/repair.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/mesh_io.h>
#include <meltlab/sim/quality.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <mutex>
#include <sstream>

namespace meltlab::sim {

namespace fs = std::filesystem;

std::string mesh_format_of(const fs::path& file) {
  std::string ext = file.extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

namespace {

bool supported_format(const std::string& ext) { return ext == "obj" || ext == "ply" || ext == "off" || ext == "stl"; }

// Collects vertices and polygons exactly as the reader delivers them.
// OpenMesh reports parse problems on its own log streams (omerr -> std::cerr, omlog ->
// std::clog, omout -> std::cout). They are redirected once, for the whole process, into a
// buffer that each read or write clears and inspects, so our one-line error can say what
// the reader saw and nothing is printed behind the user's back. (Connecting and
// disconnecting per call would leak: OpenMesh's multiplexer does not free its targets.)
class CapturedOpenMeshLog {
 public:
  CapturedOpenMeshLog() {
    static std::mutex mu;
    static std::ostringstream* buffer = [] {
      auto* b = new std::ostringstream;  // lives as long as OpenMesh's streams
      omerr().disconnect(std::cerr);
      omlog().disconnect(std::clog);
      omout().disconnect(std::cout);
      omerr().connect(*b);
      omlog().connect(*b);
      omout().connect(*b);
      return b;
    }();
    lock_ = std::unique_lock<std::mutex>(mu);
    buffer_ = buffer;
    buffer_->str({});
  }
  CapturedOpenMeshLog(const CapturedOpenMeshLog&) = delete;
  CapturedOpenMeshLog& operator=(const CapturedOpenMeshLog&) = delete;
  std::string first_error_line() const {
    std::istringstream in(buffer_->str());
    std::string line;
    while (std::getline(in, line))
      if (line.find_first_not_of(" \t\r") != std::string::npos) return line;
    return {};
  }

 private:
  std::unique_lock<std::mutex> lock_;
  std::ostringstream* buffer_ = nullptr;
};

}  // namespace

PolygonMesh read_polygon_mesh(const fs::path& file) {
  const std::string name = file.string();
  const std::string ext = mesh_format_of(file);
  std::error_code ec;
  if (fs::exists(file, ec) && !fs::is_directory(file, ec) && !supported_format(ext))
    throw InputError(fmt::format("{}: unknown mesh format '.{}' (use .obj, .ply, .off or .stl)", name, ext));
  const std::int64_t size = check_input_file(file, "mesh");
  if (!supported_format(ext))
    throw InputError(fmt::format("{}: unknown mesh format '.{}' (use .obj, .ply, .off or .stl)", name, ext));
  PolygonMesh m = ext == "off"   ? io::read_off(file, size)
                  : ext == "ply" ? io::read_ply(file, size)
                  : ext == "obj" ? io::read_obj(file)
                                 : io::read_stl(file, size);
  if (m.V.empty() || m.faces.empty())
    throw InputError(fmt::format("{}: no {} in the file", name, m.V.empty() ? "vertices" : "faces"));
  for (std::size_t v = 0; v < m.V.size(); ++v)
    if (!m.V[v].allFinite())
      throw InputError(fmt::format("{}: vertex v{} has a non-finite coordinate ({}, {}, {})", name, v, m.V[v].x(),
                                   m.V[v].y(), m.V[v].z()));
  return m;
}

LoadedMesh load_mesh(const fs::path& file, const LoadOptions& options) {
  LoadedMesh out;
  const std::string name = file.string();
  if (!(options.weld_tolerance >= 0.0) || !std::isfinite(options.weld_tolerance))
    throw InputError(fmt::format("{}: weld tolerance must be a finite number >= 0", name));
  PolygonMesh raw = read_polygon_mesh(file);
  out.report.file_vertices = raw.V.size();
  out.report.file_faces = raw.faces.size();
  WeldResult welded = weld_vertices(raw, options.weld_tolerance);
  out.report.welded_vertices = welded.merged_vertices;
  out.report.unreferenced_vertices = welded.unreferenced_removed;
  out.report.degenerate_faces = welded.degenerate_faces_removed;
  out.polygons = std::move(welded.mesh);
  if (out.polygons.faces.empty()) throw InputError(fmt::format("{}: every face is degenerate", name));
  const TopologyReport poly_topo = check_topology(out.polygons);
  out.report.file_counts = poly_topo.counts;
  out.mesh = triangulate(out.polygons, name);
  TriMesh<double> tm = TriMesh<double>::from_indexed(out.mesh);
  const TopologyReport topo = check_topology(tm);
  std::string problem;
  if (!topo.valid()) {
    problem = topo.problems.empty() ? "invalid topology" : topo.problems.front().describe();
    const std::int64_t others = topo.boundary_edges + topo.nonmanifold_edges + topo.nonmanifold_vertices +
                                topo.misoriented_edges + topo.low_valence_vertices - 1;
    if (others > 0) problem += fmt::format(" (and {} more problem(s))", others);
  } else if (mesh_volume(tm) < 0.0) {
    problem = fmt::format("inside-out: the faces are oriented inwards (volume {:.6g} < 0)", mesh_volume(tm));
  }
  if (!problem.empty()) {
    if (options.repair) {
      RepairResult repaired = repair_closed_solid(out.polygons, name);
      out.mesh = std::move(repaired.mesh);
      out.report.repairs = std::move(repaired.actions);
    } else if (options.validate) {
      throw InputError(fmt::format("{}: {}; use --repair to fix it with CGAL", name, problem));
    }
  }
  return out;
}

void save_mesh(const IndexedMesh& mesh, const fs::path& file) {
  const std::string ext = mesh_format_of(file);
  if (!supported_format(ext))
    throw InputError(fmt::format("{}: unknown mesh format '.{}' (use .obj, .ply, .off or .stl)", file.string(), ext));
  struct Traits : OpenMesh::DefaultTraits {
    using Point = OpenMesh::Vec3d;
    using Normal = OpenMesh::Vec3d;
  };
  using OMesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;
  OMesh om;
  std::vector<OMesh::VertexHandle> vh;
  vh.reserve(mesh.V.size());
  for (const auto& p : mesh.V) vh.push_back(om.add_vertex(OMesh::Point(p.x(), p.y(), p.z())));
  std::size_t dropped = 0;
  {
    CapturedOpenMeshLog capture;
    for (const auto& t : mesh.F) {
      auto fh = om.add_face(vh[static_cast<std::size_t>(t[0])], vh[static_cast<std::size_t>(t[1])],
                            vh[static_cast<std::size_t>(t[2])]);
      if (!fh.is_valid()) ++dropped;
    }
  }
  if (dropped > 0)
    throw InputError(fmt::format("{}: cannot write: {} face(s) are non-manifold", file.string(), dropped));
  OpenMesh::IO::Options opt;
  if (ext == "ply" || ext == "stl") opt += OpenMesh::IO::Options::Binary;
  write_atomically(file, [&](const fs::path& tmp) {
    bool ok = false;
    {
      CapturedOpenMeshLog capture;
      ok = OpenMesh::IO::write_mesh(om, tmp.string(), opt, 17);
    }
    if (!ok) throw InputError(fmt::format("{}: cannot write mesh", file.string()));
  });
}

}  // namespace meltlab::sim
