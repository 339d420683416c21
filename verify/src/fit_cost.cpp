// The Ceres side of the fit: one cost functor per photo (and one for the volume series),
// differentiated by central differences in the parameters' scaled units.

#include "fit_detail.h"

#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace meltlab::verify::fit_detail {

BlockCost::BlockCost(Evaluator& ev, int target, int count, double step, std::vector<double> lower_u,
                     std::vector<double> upper_u)
    : ev_(ev), target_(target), step_(step), lower_u_(std::move(lower_u)), upper_u_(std::move(upper_u)) {
  set_num_residuals(count);
  for (std::size_t j = 0; j < ev.params().size(); ++j) mutable_parameter_block_sizes()->push_back(1);
}

bool BlockCost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  // A parameter vector the model refuses (e.g. an invalid kl field) is an infeasible step.
  try {
    return evaluate(parameters, residuals, jacobians);
  } catch (const InputError&) {
    return false;
  }
}

bool BlockCost::evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const std::size_t n = ev_.params().size();
  std::vector<double> u(n);
  for (std::size_t j = 0; j < n; ++j) u[j] = parameters[j][0];
  const std::vector<double> r = residuals_at(u);
  std::copy(r.begin(), r.end(), residuals);
  if (!jacobians) return true;
  for (std::size_t j = 0; j < n; ++j) {
    if (!jacobians[j]) continue;
    // Central difference, one-sided at a bound.
    std::vector<double> up = u, down = u;
    up[j] = std::min(u[j] + step_, upper_u_[j]);
    down[j] = std::max(u[j] - step_, lower_u_[j]);
    const double h = up[j] - down[j];
    if (h <= 0) {
      for (int i = 0; i < num_residuals(); ++i) jacobians[j][i] = 0;
      continue;
    }
    const std::vector<double> rp = up[j] == u[j] ? r : residuals_at(up);
    const std::vector<double> rm = down[j] == u[j] ? r : residuals_at(down);
    for (int i = 0; i < num_residuals(); ++i)
      jacobians[j][i] = (rp[static_cast<std::size_t>(i)] - rm[static_cast<std::size_t>(i)]) / h;
  }
  return true;
}

std::vector<double> BlockCost::residuals_at(const std::vector<double>& u) const {
  std::vector<double> x(u.size());
  for (std::size_t j = 0; j < u.size(); ++j) x[j] = ev_.params()[j].initial + ev_.params()[j].scale * u[j];
  const auto e = ev_.evaluate(x);
  return target_ >= 0 ? e->frame_residuals[static_cast<std::size_t>(target_)] : e->volume_residuals;
}

ceres::CallbackReturnType LogIterations::operator()(const ceres::IterationSummary& s) {
  if (o_.log)
    o_.log(fmt::format("iteration {}: cost {:.6g}, |step| {:.3g}, {} simulations", s.iteration, s.cost, s.step_norm,
                       ev_.simulations()));
  return ceres::SOLVER_CONTINUE;
}

double huber_cost(const std::vector<double>& r, double a) {
  double s = 0;
  for (double v : r) s += v * v;
  return 0.5 * (s <= a * a ? s : 2 * a * std::sqrt(s) - a * a);
}

}  // namespace meltlab::verify::fit_detail
