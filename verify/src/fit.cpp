// The fit's stages (see fit.h for the residuals and fit_detail.h for the files):
//   check_parameters -> photo_targets -> start_registration -> Evaluator -> scan_kg ->
//   build_problem -> solve -> residual statistics -> covariance -> estimates.

#include <meltlab/core/error.h>
#include <meltlab/verify/fit.h>
#include <meltlab/verify/metrics.h>
#include <meltlab/verify/registration.h>

#include <ceres/ceres.h>
#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <set>

#include "fit_detail.h"

namespace meltlab::verify {

namespace {

using namespace fit_detail;

constexpr double kDeg = std::numbers::pi / 180.0;

bool is_registration(const std::string& name) { return fit_parameter_role(name) == FitParameterRole::kRegistration; }

/// Throws InputError for a duplicated name, a start outside the bounds or a bad scale.
void check_parameters(const std::vector<FitParameter>& params, const FitOptions& o) {
  std::set<std::string> names;
  for (const FitParameter& p : params) {
    if (!names.insert(p.name).second) throw InputError(fmt::format("fit: parameter {} given twice", p.name));
    if (!(p.lower <= p.initial && p.initial <= p.upper) || !std::isfinite(p.initial))
      throw InputError(fmt::format("fit: {} = {} is outside its bounds [{}, {}]", p.name, p.initial, p.lower, p.upper));
    if (!(p.scale > 0) || !std::isfinite(p.scale)) throw InputError(fmt::format("fit: {} needs a scale > 0", p.name));
  }
  if (o.photo_samples < 4 || o.render_samples < 1)
    throw InputError("fit: at least 4 photo and 1 render samples per frame");
}

struct Targets {
  std::vector<PhotoTarget> targets;
  cv::Mat first_mask;  ///< of the first usable photo (pivot, initial registration)
};

/// Segments every photo to fit once; unreadable or empty photos go to result.frames_refused.
Targets photo_targets(const ObservationSequence& obs, const FitOptions& o, FitResult& result) {
  Targets out;
  std::vector<int> frames = o.frames;
  if (frames.empty())
    for (const Frame& f : obs.frames) frames.push_back(f.index);
  for (const int k : frames) {
    if (k < 0 || k >= static_cast<int>(obs.frames.size())) throw InputError(fmt::format("fit: no frame {}", k + 1));
    const Frame& f = obs.frames[static_cast<std::size_t>(k)];
    cv::Mat image;
    try {
      image = read_image(f.image);
    } catch (const InputError& e) {
      result.frames_refused.push_back(fmt::format("frame {}: {}", k + 1, e.what()));
      continue;
    }
    const Segmentation seg = segment_image(image, obs.segmentation, obs.roi);
    if (seg.area_px <= 0 || seg.region.empty()) {
      result.frames_refused.push_back(fmt::format("frame {}: segmentation found no object", k + 1));
      continue;
    }
    PhotoTarget t;
    t.frame = k;
    t.position = (f.time_s && obs.interval_s) ? *f.time_s / *obs.interval_s : static_cast<double>(k);
    t.segs = segments_of(seg.region);
    t.samples = sample_contour(t.segs, o.photo_samples);
    t.area = region_area(seg.region);
    for (const Segment& s : t.segs) t.perimeter += (s.b - s.a).norm();
    const cv::Rect bound = cv::boundingRect(seg.mask);
    const int m = static_cast<int>(std::ceil(o.margin_px));
    t.bbox = cv::Rect(bound.x - m, bound.y - m, bound.width + 2 * m, bound.height + 2 * m) &
             cv::Rect(0, 0, image.cols, image.rows);
    t.sdf = signed_distance_image(seg.mask);
    if (out.first_mask.empty()) out.first_mask = seg.mask;
    out.targets.push_back(std::move(t));
    result.frames_used.push_back(k);
  }
  return out;
}

int index_of(const std::vector<FitParameter>& params, const std::string& name) {
  for (std::size_t j = 0; j < params.size(); ++j)
    if (params[j].name == name) return static_cast<int>(j);
  return -1;
}

/// Starts the free reg.* parameters from register_masks of the first photo against the model's
/// render at the starting values, expressed about the pivot.
void start_registration(const ObservationSequence& obs, FitModel& model, std::vector<FitParameter>& params,
                        const FitOptions& o, const PhotoTarget& first, const cv::Mat& first_mask, const Vec2d& pivot,
                        const std::function<void(const std::string&)>& log) {
  std::map<std::string, double> mv;
  for (const FitParameter& p : params)
    if (is_model_parameter(p.name)) mv[p.name] = p.initial;
  const int kc = index_of(params, "cycles_per_photo");
  const double K = kc >= 0 ? params[static_cast<std::size_t>(kc)].initial : kDefaultCyclesPerPhoto;
  auto seq = model.start(mv);
  const auto cycle = static_cast<std::int64_t>(std::llround(o.first_cycle + first.position * K));
  const cv::Mat render_mask = render::silhouette_mask(seq->mesh_at(cycle), obs.camera);
  if (cv::countNonZero(render_mask) <= 0) return;
  const RegistrationResult rr = register_masks(first_mask, render_mask);
  // Express it about the pivot: translation' = translation - (pivot - s R pivot).
  Similarity2D about;
  about.scale = rr.render_to_photo.scale;
  about.angle_rad = rr.render_to_photo.angle_rad;
  const Vec2d base = pivot - about.apply(pivot);
  const Vec2d t = rr.render_to_photo.translation - base;
  const std::map<std::string, double> init{{"reg.tx_px", t.x()},
                                           {"reg.ty_px", t.y()},
                                           {"reg.angle_deg", about.angle_rad / kDeg},
                                           {"reg.scale", about.scale}};
  for (FitParameter& p : params) {
    if (!is_registration(p.name) || p.fixed) continue;
    const auto it = init.find(p.name);
    if (it != init.end()) p.initial = std::clamp(it->second, p.lower, p.upper);
  }
  log(fmt::format("initial registration ({}): P {:.4f} -> {:.4f}", rr.method, rr.P_before, rr.P_after));
}

/// The solver's unknowns: u_j = (x_j - initial_j) / scale_j, with bounds in the same units.
struct ScaledParameters {
  std::vector<double> u, lower_u, upper_u;

  explicit ScaledParameters(const std::vector<FitParameter>& params)
      : u(params.size(), 0.0), lower_u(params.size()), upper_u(params.size()) {
    for (std::size_t j = 0; j < params.size(); ++j) {
      lower_u[j] = (params[j].lower - params[j].initial) / params[j].scale;
      upper_u[j] = (params[j].upper - params[j].initial) / params[j].scale;
    }
  }
  std::vector<double> values(const std::vector<FitParameter>& params, const std::vector<double>& uu) const {
    std::vector<double> x(params.size());
    for (std::size_t j = 0; j < params.size(); ++j) x[j] = params[j].initial + params[j].scale * uu[j];
    return x;
  }
};

/// The robust cost the solver minimises, at scaled parameters `uu`.
double total_cost(Evaluator& ev, const ScaledParameters& sp, const std::vector<double>& uu, double block_loss) {
  const auto e = ev.evaluate(sp.values(ev.params(), uu));
  double c = 0;
  for (const auto& r : e->frame_residuals) c += huber_cost(r, block_loss);
  for (double v : e->volume_residuals) c += 0.5 * v * v;
  return c;
}

/// Coarse scan of kg over factors of its start (guards against a local minimum of the melt
/// rate); moves u to the best.
void scan_kg(Evaluator& ev, ScaledParameters& sp, const FitOptions& o, double block_loss, FitResult& result,
             const std::function<void(const std::string&)>& log) {
  const std::vector<FitParameter>& params = ev.params();
  const int kg = index_of(params, "kg");
  if (kg < 0 || params[static_cast<std::size_t>(kg)].fixed || o.kg_scan.empty()) return;
  const auto j = static_cast<std::size_t>(kg);
  double best = std::numeric_limits<double>::infinity(), best_u = 0;
  for (const double f : o.kg_scan) {
    const double value = std::clamp(params[j].initial * f, params[j].lower, params[j].upper);
    std::vector<double> uu = sp.u;
    uu[j] = (value - params[j].initial) / params[j].scale;
    const double c = total_cost(ev, sp, uu, block_loss);
    result.kg_scan.emplace_back(value, c);
    log(fmt::format("scan kg = {:.4g}: cost {:.6g}", value, c));
    if (c < best) best = c, best_u = uu[j];
  }
  sp.u[j] = best_u;
}

struct FreeParameters {
  std::vector<std::string> names;
  std::vector<std::size_t> index;  ///< into the parameter list
};

/// One Huber-robust block per photo, a plain block for the volume series; fixed parameters
/// constant, free ones bounded. Returns the free parameters.
FreeParameters build_problem(ceres::Problem& problem, Evaluator& ev, ScaledParameters& sp, const FitOptions& o,
                             const std::optional<VolumeSeries>& volume, double block_loss) {
  const std::vector<FitParameter>& params = ev.params();
  const std::size_t n = params.size();
  std::vector<double*> blocks;
  for (std::size_t j = 0; j < n; ++j) blocks.push_back(&sp.u[j]);
  for (std::size_t t = 0; t < ev.targets().size(); ++t) {
    problem.AddResidualBlock(new BlockCost(ev, static_cast<int>(t), static_cast<int>(ev.residuals_per_frame()),
                                           o.step_fraction, sp.lower_u, sp.upper_u),
                             new ceres::HuberLoss(block_loss), blocks);
  }
  if (volume && o.volume_weight > 0 && !volume->time_s.empty())
    problem.AddResidualBlock(
        new BlockCost(ev, -1, static_cast<int>(volume->time_s.size()), o.step_fraction, sp.lower_u, sp.upper_u),
        nullptr, blocks);
  FreeParameters free;
  for (std::size_t j = 0; j < n; ++j) {
    if (params[j].fixed) {
      problem.SetParameterBlockConstant(&sp.u[j]);
      continue;
    }
    if (std::isfinite(sp.lower_u[j])) problem.SetParameterLowerBound(&sp.u[j], 0, sp.lower_u[j]);
    if (std::isfinite(sp.upper_u[j])) problem.SetParameterUpperBound(&sp.u[j], 0, sp.upper_u[j]);
    free.names.push_back(params[j].name);
    free.index.push_back(j);
  }
  return free;
}

/// Runs Ceres (when anything is free) and records cost, iterations and convergence.
void solve(ceres::Problem& problem, const Evaluator& ev, const FitOptions& o, const FreeParameters& free,
           FitResult& result) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_iterations;
  so.num_threads = 1;  // blocks share the cached simulation of each parameter vector
  // Relative changes below these are far below the parameters' uncertainty (kg ~ 0.2 %).
  so.function_tolerance = 1e-6;
  so.parameter_tolerance = 1e-5;
  so.minimizer_progress_to_stdout = false;
  so.logging_type = ceres::SILENT;
  LogIterations cb(o, ev);
  so.callbacks.push_back(&cb);
  ceres::Solver::Summary summary;
  if (!free.names.empty()) ceres::Solve(so, &problem, &summary);
  result.final_cost = free.names.empty() ? result.initial_cost : summary.final_cost;
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = free.names.empty() || summary.termination_type == ceres::CONVERGENCE;
  result.message = free.names.empty() ? "nothing to fit" : summary.message;
  result.free_names = free.names;
}

/// Per-frame RMS at the optimum and sigma = sqrt(2 cost / (m - n)), the scale of the covariance.
void residual_statistics(Evaluator& ev, const ScaledParameters& sp, const FreeParameters& free, FitResult& result) {
  std::size_t m = 0;
  const auto e = ev.evaluate(sp.values(ev.params(), sp.u));
  for (const auto& r : e->frame_residuals) {
    double s = 0;
    for (double v : r) s += v * v;
    result.frame_rms_px.push_back(std::sqrt(s / static_cast<double>(r.size())));
    m += r.size();
  }
  m += e->volume_residuals.size();
  const double dof = static_cast<double>(m) - static_cast<double>(free.names.size());
  result.residual_sigma_px = dof > 0 ? std::sqrt(2 * result.final_cost / dof) : 0.0;
}

/// Standard errors (physical units; NaN where not computable) and the correlation matrix of
/// the free parameters: Ceres' covariance scaled by the residual variance.
std::vector<double> covariance(ceres::Problem& problem, const std::vector<FitParameter>& params, ScaledParameters& sp,
                               const FreeParameters& free, FitResult& result,
                               const std::function<void(const std::string&)>& log) {
  std::vector<double> se(params.size(), std::numeric_limits<double>::quiet_NaN());
  if (free.names.empty()) return se;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;
  co.num_threads = 1;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (std::size_t a : free.index)
    for (std::size_t b : free.index) pairs.emplace_back(&sp.u[a], &sp.u[b]);
  if (!cov.Compute(pairs, &problem)) {
    log("covariance: not computable (rank-deficient Jacobian)");
    return se;
  }
  const std::size_t f = free.index.size();
  std::vector<std::vector<double>> c(f, std::vector<double>(f));
  for (std::size_t a = 0; a < f; ++a)
    for (std::size_t b = 0; b < f; ++b) cov.GetCovarianceBlock(&sp.u[free.index[a]], &sp.u[free.index[b]], &c[a][b]);
  const double var = result.residual_sigma_px * result.residual_sigma_px;
  result.correlation.assign(f, std::vector<double>(f, 0.0));
  for (std::size_t a = 0; a < f; ++a) {
    se[free.index[a]] = std::sqrt(std::max(0.0, c[a][a] * var)) * params[free.index[a]].scale;
    for (std::size_t b = 0; b < f; ++b) {
      const double d = std::sqrt(std::max(c[a][a], 0.0) * std::max(c[b][b], 0.0));
      result.correlation[a][b] = d > 0 ? c[a][b] / d : (a == b ? 1.0 : 0.0);
    }
  }
  return se;
}

std::vector<FitEstimate> estimates(const std::vector<FitParameter>& params, const std::vector<double>& u,
                                   const std::vector<double>& se) {
  std::vector<FitEstimate> out;
  for (std::size_t j = 0; j < params.size(); ++j) {
    FitEstimate e;
    e.name = params[j].name;
    e.initial = params[j].initial;
    e.value = params[j].initial + params[j].scale * u[j];
    e.fixed = params[j].fixed;
    if (!e.fixed && std::isfinite(se[j])) e.standard_error = se[j];
    const double tol = 1e-9 * params[j].scale;
    e.at_bound = !e.fixed && (std::abs(e.value - params[j].lower) < tol || std::abs(e.value - params[j].upper) < tol);
    out.push_back(e);
  }
  return out;
}

}  // namespace

Similarity2D registration_of(const std::map<std::string, double>& v, const Vec2d& pivot) {
  auto get = [&](const char* k, double d) {
    const auto it = v.find(k);
    return it == v.end() ? d : it->second;
  };
  Similarity2D t;
  t.scale = get("reg.scale", 1.0);
  t.angle_rad = get("reg.angle_deg", 0.0) * kDeg;
  t.translation = Vec2d::Zero();
  // p' = pivot + s R (p - pivot) + (tx, ty)  =>  translation = pivot - s R pivot + (tx, ty)
  t.translation = pivot - t.apply(pivot) + Vec2d(get("reg.tx_px", 0.0), get("reg.ty_px", 0.0));
  return t;
}

double FitResult::value(const std::string& name) const {
  for (const auto& e : estimates)
    if (e.name == name) return e.value;
  throw std::out_of_range("FitResult: no parameter " + name);
}

Similarity2D FitResult::registration() const {
  std::map<std::string, double> v;
  for (const auto& e : estimates) v[e.name] = e.value;
  return registration_of(v, pivot_px);
}

double FitResult::cycles_per_photo() const {
  for (const auto& e : estimates)
    if (e.name == "cycles_per_photo") return e.value;
  return kDefaultCyclesPerPhoto;
}

FitResult fit_sequence(const ObservationSequence& obs, FitModel& model, const std::vector<FitParameter>& parameters_in,
                       const FitOptions& o, const std::optional<VolumeSeries>& volume) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::function<void(const std::string&)> log = [&](const std::string& s) {
    if (o.log) o.log(s);
  };
  std::vector<FitParameter> params = parameters_in;
  check_parameters(params, o);

  FitResult result;
  Targets targets = photo_targets(obs, o, result);
  for (const auto& s : result.frames_refused) log("refused " + s);
  if (targets.targets.empty()) throw InputError(fmt::format("{}: no usable photo to fit", obs.manifest.string()));
  // Pivot: the first photo's centroid.
  const cv::Moments mo = cv::moments(targets.first_mask, true);
  result.pivot_px = Vec2d(mo.m10 / mo.m00, mo.m01 / mo.m00);

  const bool reg_free = std::any_of(params.begin(), params.end(),
                                    [](const FitParameter& p) { return is_registration(p.name) && !p.fixed; });
  if (o.initial_registration && reg_free)
    start_registration(obs, model, params, o, targets.targets.front(), targets.first_mask, result.pivot_px, log);

  Evaluator ev(obs, model, params, o, std::move(targets.targets), volume, result.pivot_px);
  {
    std::map<std::string, double> init;
    for (const FitParameter& p : params) init[p.name] = p.initial;
    ev.set_initial_registration(registration_of(init, result.pivot_px));
  }
  ScaledParameters sp(params);
  // A photo whose RMS residual exceeds huber_px is down-weighted (the loss acts on the
  // block's squared norm, which sums residuals_per_frame terms).
  const double block_loss = o.huber_px * std::sqrt(static_cast<double>(ev.residuals_per_frame()));
  scan_kg(ev, sp, o, block_loss, result, log);

  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  const FreeParameters free = build_problem(problem, ev, sp, o, volume, block_loss);
  result.initial_cost = total_cost(ev, sp, sp.u, block_loss);
  solve(problem, ev, o, free, result);

  residual_statistics(ev, sp, free, result);
  const std::vector<double> se = covariance(problem, params, sp, free, result, log);
  result.estimates = estimates(params, sp.u, se);
  result.simulations = ev.simulations();
  result.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace meltlab::verify
