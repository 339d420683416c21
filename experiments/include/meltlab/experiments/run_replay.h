#pragma once
// Replaying a `meltlab simulate` run (for compare and synth-sequence): the run's simulation
// rebuilt from its run.json, or from options, and stepped forward on request (sim::MeltReplay).

#include <meltlab/experiments/simulate_run.h>
#include <meltlab/sim/mesh_sequence.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>

namespace meltlab::experiments {

/// Replays a finished `meltlab simulate` run: rebuilds its simulation from run.json (the
/// cycle is deterministic for any thread count) and steps it forward on request. Refuses a
/// run whose input mesh or kl file changed since (content hash).
class RunReplay final : public sim::MeshSequence {
 public:
  explicit RunReplay(const std::filesystem::path& run_dir);
  /// A run that was never written: the simulation `options` describe (out_dir ignored).
  explicit RunReplay(const SimulateOptions& options);
  ~RunReplay() override;
  /// The mesh after `cycle` cycles (cycles must not decrease between calls).
  const sim::TriMesh<double>& mesh_at(std::int64_t cycle) override { return melt_->mesh_at(cycle); }
  /// Cycles the recorded run made (-1 for a run built from options).
  std::int64_t cycles_run() const { return cycles_run_; }
  /// run.json of the recorded run (null for a run built from options).
  const nlohmann::json& run_json() const { return run_; }
  const PreparedSimulation& prepared() const { return *prepared_; }

 private:
  void start(const SimulateOptions& options);

  std::unique_ptr<PreparedSimulation> prepared_;
  std::unique_ptr<sim::MeltReplay> melt_;
  nlohmann::json run_;
  std::int64_t cycles_run_ = -1;
};

}  // namespace meltlab::experiments
