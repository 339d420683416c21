#pragma once
// Pieces of the catalog shared between catalog.cpp (reading) and dataset_files.cpp
// (generating and fetching).

#include <meltlab/datasets/catalog.h>

#include <filesystem>
#include <string>
#include <vector>

namespace meltlab::datasets::detail {

struct CatalogFile {
  std::filesystem::path archive;  ///< CGAL's data.tar.gz as the catalog names it
  std::vector<DatasetEntry> entries;
};

/// Parses and validates a catalog file (see catalog.h for the errors).
CatalogFile read_catalog(const std::filesystem::path& yaml_file);

/// True if `generator` names a procedural generator that generated_mesh knows.
bool is_known_generator(const std::string& generator);

}  // namespace meltlab::datasets::detail
