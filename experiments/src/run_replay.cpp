// Replaying a finished simulate run (for compare and fit): the melt cycle is deterministic
// for any thread count, so rebuilding the simulation from run.json's options reproduces the
// run's meshes bit for bit.

#include <meltlab/core/input_file.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/simulate_run.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <fstream>
#include <variant>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

struct RunReplay::Impl {
  std::shared_ptr<const PreparedSimulation> prepared;
  std::variant<std::monostate, sim::MeltSimulator<float>, sim::MeltSimulator<double>> simulator;
  sim::TriMesh<double> current;
  std::int64_t cycle = 0;
  bool current_valid = false;
};

RunReplay::RunReplay(const fs::path& run_dir) : impl_(std::make_unique<Impl>()) {
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
  if (!fs::exists(mesh_file, ec)) throw InputError(fmt::format("{}: the run's mesh {} no longer exists", name, mesh_file));
  if (file_hash(mesh_file) != run_["mesh"].value("file_hash", ""))
    throw InputError(fmt::format("{}: the run's mesh {} has changed since the run", name, mesh_file));
  if (!o.kl_file.empty() && file_hash(o.kl_file) != run_["parameters"].value("kl_file_hash", ""))
    throw InputError(fmt::format("{}: the run's kl file {} has changed since the run", name, o.kl_file.string()));
  cycles_run_ = run_.value("cycles_run", std::int64_t{0});
  start(o);
}

RunReplay::RunReplay(const SimulateOptions& options) : impl_(std::make_unique<Impl>()) {
  cycles_run_ = -1;
  start(options);
}

RunReplay::RunReplay(std::shared_ptr<const PreparedSimulation> prepared, const sim::MeltParams& params,
                     sim::KlFieldPtr kl)
    : impl_(std::make_unique<Impl>()) {
  cycles_run_ = -1;
  impl_->prepared = std::move(prepared);
  start_simulator(params, std::move(kl));
}

void RunReplay::start(const SimulateOptions& o) {
  impl_->prepared = prepare_simulation(o, /*check_output=*/false);
  start_simulator(impl_->prepared->params, impl_->prepared->kl);
}

void RunReplay::start_simulator(const sim::MeltParams& params, sim::KlFieldPtr kl) {
  const auto& p = *impl_->prepared;
  if (p.opt.double_precision)
    impl_->simulator.emplace<sim::MeltSimulator<double>>(sim::TriMesh<double>::from_indexed(p.mesh), params, std::move(kl),
                                                         sim::Execution::kParallel);
  else
    impl_->simulator.emplace<sim::MeltSimulator<float>>(sim::TriMesh<float>::from_indexed(p.mesh), params, std::move(kl),
                                                        sim::Execution::kParallel);
}

const PreparedSimulation& RunReplay::prepared() const { return *impl_->prepared; }

RunReplay::~RunReplay() = default;

const sim::TriMesh<double>& RunReplay::mesh_at(std::int64_t cycle) {
  if (cycle < impl_->cycle)
    throw std::logic_error(fmt::format("RunReplay: cycle {} requested after cycle {}", cycle, impl_->cycle));
  std::visit(
      [&](auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (!std::is_same_v<S, std::monostate>) {
          while (impl_->cycle < cycle) {
            s.step();
            ++impl_->cycle;
            impl_->current_valid = false;
          }
          if (!impl_->current_valid) {
            if constexpr (std::is_same_v<S, sim::MeltSimulator<double>>)
              impl_->current = s.mesh();
            else
              impl_->current = s.mesh().template cast<double>();
            impl_->current_valid = true;
          }
        }
      },
      impl_->simulator);
  return impl_->current;
}

}  // namespace meltlab::experiments
