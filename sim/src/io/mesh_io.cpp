// Mesh files through OpenMesh's IO layer. Reading uses a custom importer that records the
// raw polygons (OpenMesh's own mesh types would build half-edges and silently drop faces
// that make the surface non-manifold, which is exactly what we must report).

#include "mesh_prescan.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/input_file.h>
#include <meltlab/core/limits.h>
#include <meltlab/sim/cgal/repair.h>
#include <meltlab/core/error.h>
#include <meltlab/sim/mesh_io.h>
#include <meltlab/sim/quality.h>

#include <OpenMesh/Core/IO/IOManager.hh>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
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
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

namespace {

bool supported_format(const std::string& ext) {
  return ext == "obj" || ext == "ply" || ext == "off" || ext == "stl";
}

// Collects vertices and polygons exactly as the reader delivers them.
// Stops taking elements beyond `limit` (a guard behind the prescan: whatever a reader believes
// about a file, it cannot make us store more than the limit allows).
class SoupImporter final : public OpenMesh::IO::BaseImporter {
 public:
  explicit SoupImporter(std::int64_t limit) : limit_(static_cast<std::size_t>(limit)) {}
  PolygonMesh mesh;
  std::size_t bad_index_faces = 0;
  bool over_limit = false;

  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3f& p) override {
    return add_vertex(OpenMesh::Vec3d(static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2])));
  }
  OpenMesh::VertexHandle add_vertex(const OpenMesh::Vec3d& p) override {
    if (mesh.V.size() >= limit_) {
      over_limit = true;
      return OpenMesh::VertexHandle();
    }
    mesh.V.emplace_back(p[0], p[1], p[2]);
    return OpenMesh::VertexHandle(static_cast<int>(mesh.V.size() - 1));
  }
  OpenMesh::VertexHandle add_vertex() override { return add_vertex(OpenMesh::Vec3d(0, 0, 0)); }
  OpenMesh::HalfedgeHandle add_edge(OpenMesh::VertexHandle, OpenMesh::VertexHandle) override { return OpenMesh::HalfedgeHandle(); }
  OpenMesh::FaceHandle add_face(const VHandles& idx) override {
    if (mesh.faces.size() >= limit_) {
      over_limit = true;
      return OpenMesh::FaceHandle();
    }
    PolygonFace f;
    f.outer.reserve(idx.size());
    for (const auto& vh : idx) {
      if (!vh.is_valid() || static_cast<std::size_t>(vh.idx()) >= mesh.V.size()) {
        ++bad_index_faces;
        return OpenMesh::FaceHandle();
      }
      f.outer.push_back(vh.idx());
    }
    mesh.faces.push_back(std::move(f));
    return OpenMesh::FaceHandle(static_cast<int>(mesh.faces.size() - 1));
  }
  OpenMesh::FaceHandle add_face(OpenMesh::HalfedgeHandle) override { return OpenMesh::FaceHandle(); }
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(OpenMesh::FaceHandle, OpenMesh::VertexHandle, const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(OpenMesh::FaceHandle, int) override {}
  void set_point(OpenMesh::VertexHandle vh, const OpenMesh::Vec3f& p) override {
    if (vh.is_valid() && static_cast<std::size_t>(vh.idx()) < mesh.V.size())
      mesh.V[static_cast<std::size_t>(vh.idx())] = Vec3<double>(p[0], p[1], p[2]);
  }
  void set_halfedge(OpenMesh::VertexHandle, OpenMesh::HalfedgeHandle) override {}
  void set_normal(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::VertexHandle, const OpenMesh::Vec3d&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::VertexHandle, const OpenMesh::Vec4f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec2f&) override {}
  void set_status(OpenMesh::VertexHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(OpenMesh::HalfedgeHandle, OpenMesh::HalfedgeHandle) override {}
  void set_face(OpenMesh::HalfedgeHandle, OpenMesh::FaceHandle) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec2f&) override {}
  void set_texcoord(OpenMesh::VertexHandle, const OpenMesh::Vec3f&) override {}
  void set_texcoord(OpenMesh::HalfedgeHandle, const OpenMesh::Vec3f&) override {}
  void set_status(OpenMesh::HalfedgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::EdgeHandle, const OpenMesh::Vec4f&) override {}
  void set_status(OpenMesh::EdgeHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_normal(OpenMesh::FaceHandle, const OpenMesh::Vec3d&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4uc&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec3f&) override {}
  void set_color(OpenMesh::FaceHandle, const OpenMesh::Vec4f&) override {}
  void set_status(OpenMesh::FaceHandle, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}
  std::size_t n_vertices() const override { return mesh.V.size(); }
  std::size_t n_faces() const override { return mesh.faces.size(); }
  std::size_t n_edges() const override { return 0; }

 private:
  std::size_t limit_;
};

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

PolygonMesh read_with_openmesh(const fs::path& file, const std::string& ext, std::int64_t size) {
  const std::string name = file.string();
  // Counts checked against the file's size and the limits before OpenMesh allocates anything.
  io::prescan_mesh_file(file, ext, size);
  SoupImporter importer(input_limits().mesh_elements);
  OpenMesh::IO::Options opt;
  bool ok = false;
  std::string reader_says;
  {
    CapturedOpenMeshLog capture;
    try {
      ok = OpenMesh::IO::IOManager().read(name, importer, opt);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      ok = false;
      reader_says = e.what();
    }
    if (reader_says.empty()) reader_says = capture.first_error_line();
  }
  if (importer.over_limit)
    check_count(name, "element count", input_limits().mesh_elements + 1, input_limits().mesh_elements, "mesh_elements");
  if (!ok)
    throw InputError(fmt::format("{}: cannot parse as {}{}{}", name, ext, reader_says.empty() ? "" : ": ", reader_says));
  if (importer.bad_index_faces > 0)
    throw InputError(fmt::format("{}: {} face(s) use vertex indices out of range", name, importer.bad_index_faces));
  return std::move(importer.mesh);
}

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
  PolygonMesh m;
  if (ext == "off") {
    m = io::read_off(file, size);
  } else {
    m = read_with_openmesh(file, ext, size);
  }
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
