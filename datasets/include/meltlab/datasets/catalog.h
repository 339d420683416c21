#pragma once
// The dataset catalog: every input mesh meltlab knows by name, listed in
// datasets/catalog.yaml. Three kinds:
//   cgal       — a real mesh from CGAL's data archive, installed by the Debian package
//                libcgal-demo at /usr/share/doc/libcgal-dev/data.tar.gz; `source` is the
//                archive member (e.g. data/meshes/bunny00.off). Some are closed
//                2-manifolds as they are; the others are listed with need_repair: true.
//   procedural — a shape from procedural.h; `source` names the generator and `params`
//                its arguments (e.g. uv_sphere {segments: 100, rings: 81, radius: 0.05}).
//   mold       — one of the four mold blocks of molds.h; `source` is the mold name.
//
// Files are materialised on demand in a cache folder (dataset_path): cgal members are
// extracted from the archive, procedural shapes and molds are generated and written as
// triangulated .off files (in metres). Polygon shapes with holes (the Tab. 2.3 examples)
// are written in triangulated form (V, S and G kept; use procedural.h for the polygon form).

#include <meltlab/sim/mesh.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace meltlab::datasets {

enum class DatasetKind { kCgal, kProcedural, kMold, kRefined };

/// "cgal", "procedural", "mold", "refined".
std::string dataset_kind_name(DatasetKind kind);

struct DatasetEntry {
  std::string name;  ///< unique key, e.g. "bunny00", "benchmark_b", "giraffe"
  DatasetKind kind = DatasetKind::kProcedural;
  std::string source;                         ///< archive member | generator name | mold name |
                                              ///< (refined) the dataset it refines
  std::map<std::string, std::string> params;  ///< generator arguments (procedural only), as text
  std::string description;                    ///< one line
  std::int64_t triangles = 0;                 ///< triangles after loading (cgal: load_mesh, or the file's
                                              ///< face count if need_repair); procedural: exact; mold: target
  bool closed_manifold = true;                ///< loads with sim::load_mesh as-is (closed, manifold, oriented)
  bool need_repair = false;                   ///< must be repaired before melting (see `problem`)
  std::string problem;                        ///< what is wrong with it, if need_repair
  int genus = 0;                              ///< G of Eq. 2.3 (summed over shells), if closed_manifold
  int shells = 1;                             ///< S of Eq. 2.3, if closed_manifold
};

/// Folder holding catalog.yaml: $MELTLAB_DATASETS_DIR if set, else the source folder this
/// library was built from.
std::filesystem::path datasets_dir();

/// The catalog read from datasets_dir() / "catalog.yaml".
std::vector<DatasetEntry> dataset_catalog();

/// The catalog read from `yaml_file`. Throws InputError "<file>: <problem>" if the file is
/// missing or malformed: a missing or unknown key, a bad kind, a duplicate name, a cgal
/// entry without closed_manifold, an unknown generator or mold.
std::vector<DatasetEntry> dataset_catalog(const std::filesystem::path& yaml_file);

/// The entry called `name` in dataset_catalog(); throws InputError for an unknown name.
DatasetEntry dataset_entry(const std::string& name);

/// CGAL's data archive: $MELTLAB_CGAL_DATA_ARCHIVE if set, else the `archive` path of the
/// catalog (/usr/share/doc/libcgal-dev/data.tar.gz). Not checked for existence.
std::filesystem::path cgal_data_archive();

/// Where dataset files are cached: $MELTLAB_DATA_DIR if set, else $XDG_CACHE_HOME/meltlab,
/// else $HOME/.cache/meltlab. Throws InputError if none of these variables is set. The
/// folder is not created.
std::filesystem::path default_cache_dir();

/// The mesh of a procedural, mold or refined entry, generated in memory (metres; a refined
/// entry reads its source through dataset_path(source, cache_dir), see refine.h for its
/// params loop_levels and target_triangles). Throws InputError for a cgal entry, an unknown
/// generator, a missing, unused or malformed parameter ("<name>: parameter 'rings': ...").
sim::IndexedMesh generated_mesh(const DatasetEntry& entry, const std::filesystem::path& cache_dir);

/// generated_mesh(entry, default_cache_dir()).
sim::IndexedMesh generated_mesh(const DatasetEntry& entry);

/// Path of the dataset's file in `cache_dir`, creating the file (and the folder) if it is
/// missing:
///   cgal       — <cache_dir>/<name>.<ext of the member>, extracted with
///                `tar -xzf <archive> -C <unique temp dir> <member>` (spawned, not via a
///                shell) and renamed into place;
///   procedural, mold, refined — <cache_dir>/<name>-<8 hex digits>.off, written atomically; the hex
///                digits hash the generator, its parameters and the generator revision, so
///                a changed generator never returns a stale file.
/// Safe when several threads or processes ask for the same dataset at once: each writes to
/// its own temporary name and the final rename is atomic. Throws InputError naming the
/// dataset for an unknown name, a missing archive ("install libcgal-demo:
/// ./scripts/install-deps"), a failed extraction or an unwritable cache folder.
std::filesystem::path dataset_path(const std::string& name, const std::filesystem::path& cache_dir);

/// dataset_path(name, default_cache_dir()).
std::filesystem::path dataset_path(const std::string& name);

}  // namespace meltlab::datasets
