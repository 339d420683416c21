#pragma once
// Writing the manifest of a generated observation sequence (synth-sequence, manufacture) in
// the format verify::load_observations reads (verify/observations.h), and the end of such a run.

#include <meltlab/core/provenance.h>
#include <meltlab/core/run_folder.h>
#include <meltlab/render/camera.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct SequenceManifest {
  std::string comment;  ///< first line, after "# "
  std::string object;
  double interval_s = 40;
  render::Camera camera;
  std::string ground_truth;         ///< relative path
  std::string mass_series;          ///< relative path
  std::vector<std::string> images;  ///< relative paths
};

/// Writes DIR/manifest.yaml atomically (the marker of a complete sequence: write it last).
void write_sequence_manifest(const std::filesystem::path& dir, const SequenceManifest& m);

/// The end of a generated sequence: truth/truth.json (`truth` with the run's provenance
/// finished now), then the manifest naming it as the ground truth (the marker of a complete
/// sequence, written last), then the run folder committed.
void finish_generated_sequence(RunFolder& folder, nlohmann::json truth, Provenance& provenance,
                               SequenceManifest manifest);

}  // namespace meltlab::experiments
