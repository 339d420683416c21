// MeltReplay: a MeltSimulator stepped forward on request, its mesh handed out in doubles.

#include <meltlab/sim/mesh_sequence.h>

#include <fmt/format.h>

#include <stdexcept>
#include <type_traits>
#include <variant>

namespace meltlab::sim {

struct MeltReplay::Impl {
  std::variant<MeltSimulator<float>, MeltSimulator<double>> simulator;
  TriMesh<double> current;  ///< the mesh at `cycle` in doubles (a copy for float runs)
  std::int64_t cycle = 0;
  bool current_valid = false;

  // The simulator is built in place, never moved.
  template <class Real>
  Impl(std::in_place_type_t<Real>, const IndexedMesh& initial, const MeltParams& params, KlFieldPtr kl, Execution exec)
      : simulator(std::in_place_type<MeltSimulator<Real>>, TriMesh<Real>::from_indexed(initial), params, std::move(kl),
                  exec) {}
};

MeltReplay::MeltReplay(const IndexedMesh& initial, const MeltParams& params, KlFieldPtr kl, bool double_precision,
                       Execution exec)
    : impl_(double_precision
                ? std::make_unique<Impl>(std::in_place_type<double>, initial, params, std::move(kl), exec)
                : std::make_unique<Impl>(std::in_place_type<float>, initial, params, std::move(kl), exec)) {}

MeltReplay::~MeltReplay() = default;
MeltReplay::MeltReplay(MeltReplay&&) noexcept = default;
MeltReplay& MeltReplay::operator=(MeltReplay&&) noexcept = default;

std::int64_t MeltReplay::cycle() const { return impl_->cycle; }

const TriMesh<double>& MeltReplay::mesh_at(std::int64_t cycle) {
  if (cycle < impl_->cycle)
    throw std::logic_error(fmt::format("MeltReplay: cycle {} requested after cycle {}", cycle, impl_->cycle));
  std::visit(
      [&](auto& s) {
        using S = std::decay_t<decltype(s)>;
        while (impl_->cycle < cycle) {
          s.step();
          ++impl_->cycle;
          impl_->current_valid = false;
        }
        if (!impl_->current_valid) {
          if constexpr (std::is_same_v<S, MeltSimulator<double>>)
            impl_->current = s.mesh();
          else
            impl_->current = s.mesh().template cast<double>();
          impl_->current_valid = true;
        }
      },
      impl_->simulator);
  return impl_->current;
}

}  // namespace meltlab::sim
