// MeltSimulator: one cycle = Alg. 1 -> Alg. 2 -> Alg. 3 -> repair (§3.6).

#include "workspace.h"

#include <meltlab/core/error.h>
#include <meltlab/sim/quality.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace meltlab::sim {

void MeltParams::validate() const {
  auto finite_nonneg = [](double x, const char* name) {
    if (!std::isfinite(x) || x < 0.0)
      throw InputError(fmt::format("{}: must be a finite number >= 0 (got {})", name, x));
  };
  finite_nonneg(kg, "kg");
  if (kg > 1.0) throw InputError(fmt::format("kg: must lie in [0, 1] (got {})", kg));
  finite_nonneg(kE, "kE");
  finite_nonneg(kN, "kN");
  finite_nonneg(kr, "kr");
  finite_nonneg(compact_after, "compact_after");
  if (remnant_check_every < 0) throw InputError("remnant_check_every: must be >= 0");
  if (!(compact_below >= 0.0 && compact_below <= 1.0))
    throw InputError(fmt::format("compact_below: must lie in [0, 1] (got {})", compact_below));
}

MeltParams relative_melt_params(const IndexedMesh& mesh, double ke_rel, double kr_rel, double kg) {
  const double L0 = mesh_quality(TriMesh<double>::from_indexed(mesh)).mean_edge_length;
  MeltParams p;
  p.kg = kg;
  p.kE = ke_rel * L0;
  p.kN = p.kE / 100.0;
  p.kr = kr_rel * L0;
  return p;
}

template <class Real>
MeltSimulator<Real>::MeltSimulator(TriMesh<Real> mesh, MeltParams params, KlFieldPtr kl, Execution exec)
    : mesh_(std::move(mesh)), params_(params), kl_(std::move(kl)), exec_(exec), ws_(std::make_unique<MeltWorkspace>()) {
  params_.validate();
  if (!kl_) kl_ = make_constant_kl(1.0);
  sort_triangle_indices(mesh_);  // "once: sort triangle indices" before the first cycle
  for (std::size_t v = 0; v < mesh_.vertex_slots(); ++v) mesh_.reindex[v] = static_cast<Index>(v);
  prepare_workspace(*ws_, mesh_);
  ws_->record_vectors = false;
}

template <class Real>
MeltSimulator<Real>::~MeltSimulator() = default;
template <class Real>
MeltSimulator<Real>::MeltSimulator(MeltSimulator&&) noexcept = default;
template <class Real>
MeltSimulator<Real>& MeltSimulator<Real>::operator=(MeltSimulator&&) noexcept = default;

template <class Real>
void MeltSimulator<Real>::set_params(const MeltParams& p) {
  p.validate();
  params_ = p;
}

template <class Real>
void MeltSimulator<Real>::set_sweep_parts(std::size_t parts) {
  ws_->deform_parts = parts;
}

template <class Real>
void MeltSimulator<Real>::set_record_vectors(bool on) {
  ws_->record_vectors = on;
}

template <class Real>
bool MeltSimulator<Real>::record_vectors() const {
  return ws_->record_vectors;
}

template <class Real>
bool MeltSimulator<Real>::empty() const {
  return std::find(mesh_.triangle_alive.begin(), mesh_.triangle_alive.end(), 1) == mesh_.triangle_alive.end();
}

template <class Real>
CycleReport MeltSimulator<Real>::step() {
  CycleReport r;
  MeltWorkspace& ws = *ws_;
  using Clock = std::chrono::steady_clock;
  auto ms_since = [](Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  };
  auto t = Clock::now();
  deform_pass(mesh_, params_, *kl_, exec_, ws);
  r.deform_ms = ms_since(t);
  t = Clock::now();
  collapse_pass(mesh_, params_.kr, params_.merge, exec_, ws, r);
  r.collapse_ms = ms_since(t);
  // Without a merge the connectivity is unchanged: no glued pairs can have appeared and the
  // triangles are still sorted, so Alg. 3 and the repair would find nothing to do.
  if (r.merged_vertices > 0) {
    t = Clock::now();
    glued_pass(mesh_, ws, r);
    r.glued_ms = ms_since(t);
    t = Clock::now();
    if (params_.repair) repair_pass(mesh_, ws, r, exec_);
    r.repair_ms = ms_since(t);
  }
  ws.schedule.touch(ws.dirty_list);  // their triangle lists changed
  ws.clear_dirty();
  if (params_.remnant_check_every > 0 && (cycle_ + 1) % params_.remnant_check_every == 0) {
    t = Clock::now();
    r.inverted_parts_removed = remove_inverted_parts_pass(mesh_, ws, exec_);
    r.remnant_ms = ms_since(t);
  }
  r.live_vertices = static_cast<std::int64_t>(mesh_.live_vertex_count());
  r.live_triangles = static_cast<std::int64_t>(mesh_.live_triangle_count());
  const auto slots = static_cast<double>(mesh_.triangle_slots());
  if (slots > 0) {
    const auto live = static_cast<double>(r.live_triangles);
    dead_share_sum_ += 1.0 - live / slots;
    if ((params_.compact_below > 0.0 && live < params_.compact_below * slots) ||
        (params_.compact_after > 0.0 && dead_share_sum_ >= params_.compact_after)) {
      t = Clock::now();
      compact_workspace(mesh_, ws, exec_);
      r.compact_ms = ms_since(t);
      r.compacted = true;
      dead_share_sum_ = 0;
    }
  }
  ++cycle_;
  return r;
}

template class MeltSimulator<float>;
template class MeltSimulator<double>;

}  // namespace meltlab::sim
