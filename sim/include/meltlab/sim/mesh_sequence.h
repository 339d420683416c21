#pragma once
// A melting mesh over time: the mesh after any number of cycles, read forward in cycle order
// (by the comparison with photos, the fit and the synthetic sequences).

#include <meltlab/sim/melt.h>
#include <meltlab/sim/mesh.h>

#include <cstdint>
#include <memory>

namespace meltlab::sim {

/// The simulated meshes, cycle by cycle. Cycles are requested in non-decreasing order.
class MeshSequence {
 public:
  virtual ~MeshSequence() = default;
  /// The mesh after `cycle` cycles (possibly empty if it has melted away).
  virtual const TriMesh<double>& mesh_at(std::int64_t cycle) = 0;
};

/// A melt stepped forward on request: the simulator on `initial` with `params` and `kl`, in
/// float or double positions. The melt cycle is deterministic for any thread count, so the
/// same inputs reproduce a recorded run's meshes bit for bit.
class MeltReplay final : public MeshSequence {
 public:
  MeltReplay(const IndexedMesh& initial, const MeltParams& params, KlFieldPtr kl, bool double_precision,
             Execution exec = Execution::kParallel);
  ~MeltReplay() override;
  MeltReplay(MeltReplay&&) noexcept;
  MeltReplay& operator=(MeltReplay&&) noexcept;

  /// The mesh after `cycle` cycles; throws std::logic_error if `cycle` is below a cycle
  /// already reached (the melt only runs forward).
  const TriMesh<double>& mesh_at(std::int64_t cycle) override;
  /// Cycles run so far.
  std::int64_t cycle() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meltlab::sim
