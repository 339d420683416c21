#include <meltlab/experiments/sequence_manifest.h>
#include <meltlab/experiments/provenance.h>
#include <meltlab/experiments/render_json.h>
#include <meltlab/core/atomic_file.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <sstream>

namespace meltlab::experiments {

void write_sequence_manifest(const std::filesystem::path& dir, const SequenceManifest& m) {
  using nlohmann::json;
  std::ostringstream out;
  out << "# " << m.comment << "\n"
      << "meltlab_observations: 1\n"
      << "object: " << json(m.object).dump() << "\n"
      << "interval_s: " << fmt::format("{}", m.interval_s) << "\n"
      << "camera: " << camera_json(m.camera).dump() << "\n";
  if (!m.ground_truth.empty()) out << "ground_truth: " << json(m.ground_truth).dump() << "\n";
  if (!m.mass_series.empty()) out << "mass_series: " << json(m.mass_series).dump() << "\n";
  out << "frames:\n";
  for (const std::string& image : m.images) out << "  - {image: " << json(image).dump() << "}\n";
  write_text_atomically(dir / "manifest.yaml", out.str());
}

void finish_generated_sequence(RunFolder& folder, nlohmann::json truth, Provenance& provenance,
                               SequenceManifest manifest) {
  const std::filesystem::path& dir = folder.path();
  truth["provenance"] = finish_provenance(provenance);
  write_text_atomically(dir / "truth" / "truth.json", truth.dump(2) + "\n");
  manifest.ground_truth = "truth/truth.json";
  write_sequence_manifest(dir, manifest);
  folder.commit();
}

}  // namespace meltlab::experiments
