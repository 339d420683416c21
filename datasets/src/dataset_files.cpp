// Materialising datasets as files (catalog.h): generating procedural shapes and molds,
// extracting CGAL's meshes from its data archive, caching both.

#include <meltlab/core/hash.h>
#include <meltlab/datasets/catalog.h>
#include <meltlab/datasets/mesh_transforms.h>
#include <meltlab/datasets/molds.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/datasets/refine.h>
#include <meltlab/core/error.h>
#include <meltlab/core/process.h>
#include <meltlab/sim/mesh_io.h>

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>

#include "catalog_internal.h"

namespace meltlab::datasets {

namespace fs = std::filesystem;
using sim::IndexedMesh;

namespace {

// Bump when any generator or mold outline changes its output, so cached files made by an
// older build are not reused (the revision is part of the cached file's name).
constexpr int kGeneratorRevision = 1;

// ---- generator parameters ----

// The `params` of a catalog entry, read with defaults at the read site; a key that no
// generator reads is an error (a typo must not pass silently).
class Params {
 public:
  explicit Params(const DatasetEntry& entry) : entry_(entry) {}

  double number(const std::string& key) { return parse_number(key, text(key)); }
  double number_or(const std::string& key, double fallback) {
    return entry_.params.count(key) ? number(key) : fallback;
  }
  int integer(const std::string& key) {
    const std::string& s = text(key);
    int v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size())
      throw InputError(fmt::format("{}: parameter '{}' must be an integer, got '{}'", entry_.name, key, s));
    return v;
  }
  int integer_or(const std::string& key, int fallback) { return entry_.params.count(key) ? integer(key) : fallback; }
  char letter(const std::string& key) {
    const std::string& s = text(key);
    if (s.size() != 1)
      throw InputError(fmt::format("{}: parameter '{}' must be one letter, got '{}'", entry_.name, key, s));
    return s[0];
  }
  void require_all_used() const {
    for (const auto& [key, value] : entry_.params)
      if (!used_.count(key))
        throw InputError(fmt::format("{}: unknown parameter '{}' for generator {}", entry_.name, key, entry_.source));
  }

 private:
  const std::string& text(const std::string& key) {
    auto it = entry_.params.find(key);
    if (it == entry_.params.end())
      throw InputError(fmt::format("{}: generator {} needs parameter '{}'", entry_.name, entry_.source, key));
    used_.insert(key);
    return it->second;
  }
  double parse_number(const std::string& key, const std::string& s) const {
    double v = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || end != s.data() + s.size())
      throw InputError(fmt::format("{}: parameter '{}' must be a number, got '{}'", entry_.name, key, s));
    return v;
  }

  const DatasetEntry& entry_;
  std::set<std::string> used_;
};

using Generator = std::function<IndexedMesh(Params&)>;

const std::map<std::string, Generator>& generators() {
  static const std::map<std::string, Generator> table = {
      {"cube_quads", [](Params& p) { return triangulated_with_holes(cube_quads(p.number_or("edge", 1.0))); }},
      {"cube_triangles", [](Params& p) { return cube_triangles(p.number_or("edge", 1.0)); }},
      {"double_cube_quads",
       [](Params& p) { return triangulated_with_holes(double_cube_quads(p.number_or("edge", 1.0))); }},
      {"cube_with_face_hole",
       [](Params& p) { return triangulated_with_holes(cube_with_face_hole(p.number_or("edge", 1.0))); }},
      {"cube_with_tunnel",
       [](Params& p) { return triangulated_with_holes(cube_with_tunnel(p.number_or("edge", 1.0))); }},
      {"cube_with_tunnel_front_triangulated",
       [](Params& p) {
         return triangulated_with_holes(cube_with_tunnel_front_triangulated(p.number_or("edge", 1.0)));
       }},
      {"subdivided_cube", [](Params& p) { return subdivided_cube(p.integer("n"), p.number_or("edge", 1.0)); }},
      {"uv_sphere",
       [](Params& p) { return uv_sphere(p.integer("segments"), p.integer("rings"), p.number_or("radius", 1.0)); }},
      {"icosphere", [](Params& p) { return icosphere(p.integer("subdivisions"), p.number_or("radius", 1.0)); }},
      {"sphere_with_triangles",
       [](Params& p) { return sphere_with_triangles(p.integer("triangles"), p.number_or("radius", 1.0)); }},
      {"torus",
       [](Params& p) {
         return torus(p.number("major_radius"), p.number("minor_radius"), p.integer("major_segments"),
                      p.integer("minor_segments"));
       }},
      {"dumbbell",
       [](Params& p) {
         DumbbellOptions o;
         o.ball_radius_m = p.number_or("ball_radius_m", o.ball_radius_m);
         o.ball_gap_m = p.number_or("ball_gap_m", o.ball_gap_m);
         o.neck_radius_m = p.number_or("neck_radius_m", o.neck_radius_m);
         o.fillet_radius_m = p.number_or("fillet_radius_m", o.fillet_radius_m);
         o.edge_length_m = p.number_or("edge_length_m", o.edge_length_m);
         return dumbbell(o);
       }},
      {"benchmark_object", [](Params& p) { return benchmark_object(p.letter("which")); }},
  };
  return table;
}

IndexedMesh mold_entry_mesh(const DatasetEntry& entry, Params& p) {
  MoldOptions o;
  o.target_triangles = p.integer_or("target_triangles", o.target_triangles);
  o.ice_mass_kg = p.number_or("ice_mass_kg", o.ice_mass_kg);
  o.ice_density_kg_m3 = p.number_or("ice_density_kg_m3", o.ice_density_kg_m3);
  o.thickness_m = p.number_or("thickness_m", o.thickness_m);
  return mold_mesh(mold_from_name(entry.source), o);
}

// ---- cache file names ----

fs::path generated_file_name(const DatasetEntry& e) {
  std::string key = fmt::format("{}\n{}\nrevision={}\n", dataset_kind_name(e.kind), e.source, kGeneratorRevision);
  for (const auto& [k, v] : e.params) key += fmt::format("{}={}\n", k, v);
  return fmt::format("{}-{:08x}.off", e.name,
                     static_cast<std::uint32_t>(ContentHash().add_bytes(key).value() & 0xffffffffu));
}

bool usable_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec) && fs::file_size(p, ec) > 0 && !ec;
}

std::string first_line_of(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) return line;
  return {};
}

// Removes a folder tree when it goes out of scope.
class ScopedFolder {
 public:
  explicit ScopedFolder(fs::path p) : path_(std::move(p)) {}
  ~ScopedFolder() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScopedFolder(const ScopedFolder&) = delete;
  ScopedFolder& operator=(const ScopedFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

fs::path extracted_cgal_file(const DatasetEntry& e, const fs::path& cache_dir) {
  const fs::path target = cache_dir / (e.name + fs::path(e.source).extension().string());
  if (usable_file(target)) return target;
  const fs::path archive = cgal_data_archive();
  std::error_code ec;
  if (!fs::is_regular_file(archive, ec))
    throw InputError(fmt::format("{}: CGAL data archive {} not found; install libcgal-demo: ./scripts/install-deps",
                                 e.name, archive.string()));
  // A temporary folder beside the target (same file system, so the rename is atomic),
  // unique per call: concurrent extractions of the same member never see each other.
  std::string pattern = (cache_dir / fmt::format(".extract-{}-XXXXXX", e.name)).string();
  if (!::mkdtemp(pattern.data()))
    throw InputError(fmt::format("{}: cannot create a temporary folder in {}: {}", e.name, cache_dir.string(),
                                 std::strerror(errno)));
  const ScopedFolder tmp(pattern);
  const fs::path log = tmp.path() / "tar.stderr";
  ProcessSpec spec;
  spec.argv = {"tar", "-xzf", archive.string(), "-C", tmp.path().string(), "--no-same-owner", e.source};
  spec.stdout_file = kNullDevice;
  spec.stderr_file = log;
  ProcessStatus tar;
  try {
    tar = run_process(spec);
  } catch (const InputError& ex) {
    throw InputError(fmt::format("{}: {}", e.name, ex.what()));
  }
  const int status = tar.shell_status();
  if (status != 0) {
    const std::string says = first_line_of(log);
    throw InputError(fmt::format("{}: extracting {} from {} failed (tar exit status {}){}{}", e.name, e.source,
                                 archive.string(), status, says.empty() ? "" : ": ", says));
  }
  const fs::path extracted = tmp.path() / e.source;
  if (!usable_file(extracted))
    throw InputError(fmt::format("{}: {} is not in {} or is empty; reinstall libcgal-demo: ./scripts/install-deps",
                                 e.name, e.source, archive.string()));
  fs::rename(extracted, target, ec);
  if (ec)
    throw InputError(
        fmt::format("{}: cannot move the extracted file to {}: {}", e.name, target.string(), ec.message()));
  return target;
}

// Serialises generation within the process: sim::save_mesh's temporary file name is unique
// per process, not per thread.
std::mutex& generation_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

namespace detail {

bool is_known_generator(const std::string& generator) { return generators().count(generator) > 0; }

}  // namespace detail

IndexedMesh generated_mesh(const DatasetEntry& entry, const fs::path& cache_dir) {
  Params params(entry);
  IndexedMesh mesh;
  switch (entry.kind) {
    case DatasetKind::kCgal:
      throw InputError(fmt::format("{}: a cgal dataset is a file, not generated; use dataset_path", entry.name));
    case DatasetKind::kProcedural: {
      auto it = generators().find(entry.source);
      if (it == generators().end())
        throw InputError(fmt::format("{}: unknown generator '{}'", entry.name, entry.source));
      mesh = it->second(params);
      break;
    }
    case DatasetKind::kMold:
      mesh = mold_entry_mesh(entry, params);
      break;
    case DatasetKind::kRefined: {
      const int levels = static_cast<int>(params.integer("loop_levels"));
      const std::int64_t target = params.integer_or("target_triangles", 0);
      try {
        // A source marked need_repair (the ChineseDragon has a small hole) is repaired on load.
        sim::LoadOptions load;
        load.repair = dataset_entry(entry.source).need_repair;
        mesh = refined(sim::load_mesh(dataset_path(entry.source, cache_dir), load).mesh, levels, target);
      } catch (const InputError& e) {
        throw InputError(fmt::format("{}: {}", entry.name, e.what()));
      }
      break;
    }
  }
  params.require_all_used();
  return mesh;
}

IndexedMesh generated_mesh(const DatasetEntry& entry) { return generated_mesh(entry, default_cache_dir()); }

fs::path dataset_path(const std::string& name, const fs::path& cache_dir) {
  const DatasetEntry e = dataset_entry(name);
  std::error_code ec;
  fs::create_directories(cache_dir, ec);
  if (ec || !fs::is_directory(cache_dir, ec))
    throw InputError(fmt::format("{}: cannot create the dataset cache folder {}: {}", name, cache_dir.string(),
                                 ec ? ec.message() : "not a folder"));
  if (e.kind == DatasetKind::kCgal) return extracted_cgal_file(e, cache_dir);
  const fs::path target = cache_dir / generated_file_name(e);
  if (usable_file(target)) return target;
  // A refined entry's source is fetched before the lock (dataset_path takes it too).
  if (e.kind == DatasetKind::kRefined) (void)dataset_path(e.source, cache_dir);
  const std::lock_guard<std::mutex> lock(generation_mutex());
  if (usable_file(target)) return target;  // another thread made it meanwhile
  sim::save_mesh(generated_mesh(e, cache_dir), target);
  return target;
}

fs::path dataset_path(const std::string& name) { return dataset_path(name, default_cache_dir()); }

}  // namespace meltlab::datasets
