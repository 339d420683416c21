// Replaying a finished simulate run (for compare and synth-sequence): the melt cycle is
// deterministic for any thread count, so rebuilding the simulation from run.json's options
// reproduces the run's meshes bit for bit (the stepping is sim::MeltReplay's).

#include <meltlab/core/input_file.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/run_replay.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

RunReplay::RunReplay(const fs::path& run_dir) {
  const fs::path file = run_dir / "run.json";
  const std::string name = file.string();
  std::error_code no_file;
  if (!fs::exists(file, no_file))
    throw InputError(fmt::format("{}: no such file (is {} a simulate run folder?)", name, run_dir.string()));
  const std::string text = read_text_file(file, "run record");
  try {
    run_ = json::parse(text);
  } catch (const json::exception& e) {
    throw InputError(fmt::format("{}: invalid JSON: {}", name, e.what()));
  }
  if (!run_.contains("options") || !run_.contains("mesh"))
    throw InputError(fmt::format("{}: not a meltlab simulate run (no options/mesh record)", name));
  SimulateOptions o = options_from_json(run_["options"], name);
  const std::string mesh_file = run_["mesh"].value("file", "");
  o.mesh = mesh_file;
  std::error_code ec;
  if (!fs::exists(mesh_file, ec))
    throw InputError(fmt::format("{}: the run's mesh {} no longer exists", name, mesh_file));
  if (file_hash(mesh_file) != run_["mesh"].value("file_hash", ""))
    throw InputError(fmt::format("{}: the run's mesh {} has changed since the run", name, mesh_file));
  if (!o.kl_file.empty() && file_hash(o.kl_file) != run_["parameters"].value("kl_file_hash", ""))
    throw InputError(fmt::format("{}: the run's kl file {} has changed since the run", name, o.kl_file.string()));
  cycles_run_ = run_.value("cycles_run", std::int64_t{0});
  start(o);
}

RunReplay::RunReplay(const SimulateOptions& options) { start(options); }

RunReplay::~RunReplay() = default;

void RunReplay::start(const SimulateOptions& o) {
  prepared_ = prepare_simulation(o, /*check_output=*/false);
  melt_ = std::make_unique<sim::MeltReplay>(prepared_->mesh, prepared_->params, prepared_->kl,
                                            prepared_->opt.double_precision, sim::Execution::kParallel);
}

}  // namespace meltlab::experiments
