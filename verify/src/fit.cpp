// The fit's stages (see fit.h for the residuals and fit_detail.h for the files):
//   check_parameters -> photo_targets -> start_registration -> Evaluator -> scan_kg ->
//   build_problem -> solve -> residual statistics -> covariance -> estimates.

#include <meltlab/core/error.h>
#include <meltlab/verify/fit.h>
#include <meltlab/verify/metrics.h>
#include <meltlab/verify/registration.h>
#include <meltlab/sim/quality.h>

#include <ceres/ceres.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
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

/// A photo as the fit sees it, from its segmentation.
PhotoTarget make_target(const ObservationSequence& obs, int k, const cv::Mat& image, const Segmentation& seg,
                        const FitOptions& o) {
  const Frame& f = obs.frames[static_cast<std::size_t>(k)];
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
  return t;
}

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
    PhotoTarget t = make_target(obs, k, image, seg, o);
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
                                   const std::vector<double>& se, const std::vector<double>& se_clustered,
                                   const std::vector<double>& segmentation) {
  std::vector<FitEstimate> out;
  for (std::size_t j = 0; j < params.size(); ++j) {
    FitEstimate e;
    e.name = params[j].name;
    e.initial = params[j].initial;
    e.value = params[j].initial + params[j].scale * u[j];
    e.fixed = params[j].fixed;
    if (!e.fixed && std::isfinite(se[j])) e.standard_error = se[j];
    if (!e.fixed && std::isfinite(se_clustered[j])) e.standard_error_clustered = se_clustered[j];
    if (!e.fixed && std::isfinite(segmentation[j])) e.segmentation_bias = segmentation[j];
    if (e.standard_error_clustered)
      e.standard_error_total = std::hypot(*e.standard_error_clustered, e.segmentation_bias.value_or(0.0));
    const double tol = 1e-9 * params[j].scale;
    e.at_bound = !e.fixed && (std::abs(e.value - params[j].lower) < tol || std::abs(e.value - params[j].upper) < tol);
    out.push_back(e);
  }
  return out;
}

bool is_free(const std::vector<FitParameter>& params, const std::string& name) {
  const int j = index_of(params, name);
  return j >= 0 && !params[static_cast<std::size_t>(j)].fixed;
}

/// A series alone: the parameters it can identify, checked before any simulation.
void check_series_parameters(const ObservationSequence& obs, const std::vector<FitParameter>& params,
                             const std::optional<VolumeSeries>& volume, const FitOptions& o) {
  if (!volume || volume->time_s.empty() || !(o.volume_weight > 0) || !volume->initial_volume_m3)
    throw InputError(fmt::format("{}: no photos and no mass series to fit", obs.manifest.string()));
  for (const FitParameter& p : params)
    if (!p.fixed && (is_registration(p.name) || p.name == "cycles_per_photo"))
      throw InputError(fmt::format("fit: {} needs photos ({} has a mass series only)", p.name, obs.manifest.string()));
  if (index_of(params, "seconds_per_cycle") < 0)
    throw InputError("fit: a mass series needs the time scale seconds_per_cycle");
  if (is_free(params, "kg") && is_free(params, "seconds_per_cycle"))
    throw InputError(
        "fit: kg and seconds_per_cycle cannot both be fitted to a mass series: it shows only the melt per second "
        "(kg / seconds_per_cycle); fix one of them: --fix seconds_per_cycle=S (seconds per cycle known) to fit kg, "
        "or --fix kg=V to fit the time scale");
  const auto n_free = std::count_if(params.begin(), params.end(), [](const FitParameter& p) { return !p.fixed; });
  if (static_cast<std::size_t>(n_free) >= volume->time_s.size())
    throw InputError(fmt::format("fit: {} readings cannot fit {} parameters", volume->time_s.size(), n_free));
}

/// A series alone with seconds_per_cycle free and no given start: the model at its starting
/// values, run until it falls to the relative volume of the reading nearest half the initial
/// one (or the last reading); S = that reading's time / the cycle it is reached at. Returns
/// the simulations run (0 or 1).
int start_time_scale(FitModel& model, std::vector<FitParameter>& params, const VolumeSeries& vs, const FitOptions& o,
                     const std::function<void(const std::string&)>& log) {
  const int j = index_of(params, "seconds_per_cycle");
  if (j < 0 || params[static_cast<std::size_t>(j)].fixed || !o.start_time_scale) return 0;
  FitParameter& S = params[static_cast<std::size_t>(j)];
  const double v0 = *vs.initial_volume_m3;
  std::size_t ref = vs.time_s.size();
  for (std::size_t i = 0; i < vs.time_s.size(); ++i) {
    if (!(vs.time_s[i] > 0)) continue;
    if (ref == vs.time_s.size() || std::abs(vs.volume_m3[i] / v0 - 0.5) < std::abs(vs.volume_m3[ref] / v0 - 0.5))
      ref = i;
  }
  if (ref == vs.time_s.size() || !(vs.volume_m3[ref] / v0 < 0.999)) {
    log("time scale start: the series shows no melt; seconds_per_cycle starts at its given value");
    return 0;
  }
  const double target = vs.volume_m3[ref] / v0;
  std::map<std::string, double> mv;
  for (const FitParameter& p : params)
    if (is_model_parameter(p.name)) mv[p.name] = p.initial;
  auto seq = model.start(mv);
  auto volume_of = [&](std::int64_t c) {
    const sim::TriMesh<double>& m = seq->mesh_at(c);
    return m.live_triangle_count() > 0 ? sim::mesh_volume(m) : 0.0;
  };
  const double mesh0 = volume_of(0);
  if (!(mesh0 > 0)) throw InputError("fit: the mesh encloses no volume at cycle 0");
  const std::int64_t first = static_cast<std::int64_t>(std::ceil(o.first_cycle));
  double previous = 1.0;
  for (std::int64_t c = std::max<std::int64_t>(first, 1); c <= o.max_cycles; ++c) {
    const double rel = volume_of(c) / mesh0;
    if (rel <= target) {
      const double frac = previous > rel ? (previous - target) / (previous - rel) : 1.0;
      const double cycle = static_cast<double>(c - 1) + frac;
      if (!(cycle > o.first_cycle)) break;
      const double start = std::clamp(vs.time_s[ref] / (cycle - o.first_cycle), S.lower, S.upper);
      log(
          fmt::format("time scale start: the model falls to {:.3f} of its volume at cycle {:.1f}, the series at {} s: "
                      "seconds_per_cycle {:.6g}",
                      target, cycle, vs.time_s[ref], start));
      S.initial = start;
      S.scale = 0.05 * start;  // the table's 5 % of the start
      return 1;
    }
    previous = rel;
  }
  throw InputError(
      fmt::format("fit: the model at its starting values does not melt to {:.3f} of its volume within {} cycles; give "
                  "the start of seconds_per_cycle (--seconds-per-cycle or --initial)",
                  target, o.max_cycles));
}

/// A small dense matrix (free x free or rows x free), row-major. The fits have a handful of
/// free parameters, so plain loops serve; Eigen's vectorised kernels trip GCC 12's
/// -Wmaybe-uninitialized under -march=native.
struct Dense {
  std::size_t rows = 0, cols = 0;
  std::vector<double> v;
  Dense() = default;
  Dense(std::size_t r, std::size_t c) : rows(r), cols(c), v(r * c, 0.0) {}
  double& operator()(std::size_t i, std::size_t j) { return v[i * cols + j]; }
  double operator()(std::size_t i, std::size_t j) const { return v[i * cols + j]; }
};

/// The inverse of a square matrix by Gauss-Jordan elimination with full pivoting; nullopt if
/// a pivot falls below 1e-12 of the largest (numerically singular).
std::optional<Dense> inverse(Dense a) {
  const std::size_t n = a.rows;
  Dense inv(n, n);
  for (std::size_t i = 0; i < n; ++i) inv(i, i) = 1.0;
  std::vector<std::size_t> col_of(n);
  for (std::size_t i = 0; i < n; ++i) col_of[i] = i;
  double largest = 0;
  for (double x : a.v) largest = std::max(largest, std::abs(x));
  if (!(largest > 0)) return std::nullopt;
  // Full pivoting: swap rows of a and inv; swap columns of a, recorded to unswap inv's rows.
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t pr = k, pc = k;
    for (std::size_t i = k; i < n; ++i)
      for (std::size_t j = k; j < n; ++j)
        if (std::abs(a(i, j)) > std::abs(a(pr, pc))) pr = i, pc = j;
    if (!(std::abs(a(pr, pc)) > 1e-12 * largest)) return std::nullopt;
    for (std::size_t j = 0; j < n; ++j) std::swap(a(k, j), a(pr, j)), std::swap(inv(k, j), inv(pr, j));
    for (std::size_t i = 0; i < n; ++i) std::swap(a(i, k), a(i, pc));
    std::swap(col_of[k], col_of[pc]);
    const double d = a(k, k);
    for (std::size_t j = 0; j < n; ++j) a(k, j) /= d, inv(k, j) /= d;
    for (std::size_t i = 0; i < n; ++i) {
      if (i == k || a(i, k) == 0) continue;
      const double m = a(i, k);
      for (std::size_t j = 0; j < n; ++j) a(i, j) -= m * a(k, j), inv(i, j) -= m * inv(k, j);
    }
  }
  // a was reduced to the identity with its columns permuted by col_of: the inverse of the
  // original has row col_of[k] = row k of inv.
  Dense out(n, n);
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t j = 0; j < n; ++j) out(col_of[k], j) = inv(k, j);
  return out;
}

Dense multiply(const Dense& a, const Dense& b) {
  Dense c(a.rows, b.cols);
  for (std::size_t i = 0; i < a.rows; ++i)
    for (std::size_t k = 0; k < a.cols; ++k)
      for (std::size_t j = 0; j < b.cols; ++j) c(i, j) += a(i, k) * b(k, j);
  return c;
}

/// Residual blocks with their Jacobians in the free parameters' scaled units, at u.
struct Blocks {
  std::vector<std::vector<double>> r;
  std::vector<Dense> J;  ///< rows x free
};

/// Central differences as BlockCost's (one-sided at a bound) of the blocks `residuals(x)`.
Blocks blocks_at(const std::function<std::vector<std::vector<double>>(const std::vector<double>&)>& residuals,
                 const std::vector<FitParameter>& params, const ScaledParameters& sp, const std::vector<double>& u,
                 const FreeParameters& free, double step) {
  Blocks b;
  b.r = residuals(sp.values(params, u));
  for (const auto& r : b.r) b.J.emplace_back(r.size(), free.index.size());
  for (std::size_t a = 0; a < free.index.size(); ++a) {
    const std::size_t j = free.index[a];
    std::vector<double> up = u, down = u;
    up[j] = std::min(u[j] + step, sp.upper_u[j]);
    down[j] = std::max(u[j] - step, sp.lower_u[j]);
    const double h = up[j] - down[j];
    if (h <= 0) continue;
    const auto rp = up[j] == u[j] ? b.r : residuals(sp.values(params, up));
    const auto rm = down[j] == u[j] ? b.r : residuals(sp.values(params, down));
    for (std::size_t k = 0; k < b.r.size(); ++k)
      for (std::size_t i = 0; i < b.r[k].size(); ++i) b.J[k](i, a) = (rp[k][i] - rm[k][i]) / h;
  }
  return b;
}

/// The blocks the solver sees: one per photo, then the volume series (if any).
std::vector<std::vector<double>> evaluation_blocks(Evaluator& ev, const std::vector<double>& x) {
  const auto e = ev.evaluate(x);
  std::vector<std::vector<double>> out = e->frame_residuals;
  if (!e->volume_residuals.empty()) out.push_back(e->volume_residuals);
  return out;
}

/// Huber weight of a block (the IRLS weight rho'(|r|²) of Ceres' HuberLoss).
double huber_weight(const std::vector<double>& r, double a) {
  double s = 0;
  for (double v : r) s += v * v;
  return s <= a * a ? 1.0 : a / std::sqrt(s);
}

/// A cluster of residuals: its rows of one block, and the block's Huber weight.
struct Cluster {
  std::size_t block = 0, row0 = 0, rows = 0;
  double weight = 1;
};

/// Clusters: every photo block; the volume block of a photo fit as one; a series alone in
/// runs of consecutive readings.
std::vector<Cluster> clusters_of(const Blocks& b, std::size_t photo_blocks, double block_loss, bool series_only,
                                 const FitOptions& o, int& readings_per_cluster) {
  std::vector<Cluster> out;
  for (std::size_t k = 0; k < b.r.size(); ++k) {
    if (k < photo_blocks) {
      out.push_back({k, 0, b.r[k].size(), huber_weight(b.r[k], block_loss)});
    } else if (!series_only) {
      out.push_back({k, 0, b.r[k].size(), 1.0});
    } else {
      const std::size_t n = b.r[k].size();
      const auto size = static_cast<std::size_t>(o.series_cluster_size > 0
                                                     ? o.series_cluster_size
                                                     : std::max(1L, std::lround(std::cbrt(static_cast<double>(n)))));
      readings_per_cluster = static_cast<int>(size);
      for (std::size_t i = 0; i < n; i += size) out.push_back({k, i, std::min(size, n - i), 1.0});
    }
  }
  return out;
}

/// A = Σ w J_kᵀ J_k over the clusters (the Gauss-Newton matrix of the robust cost).
Dense gauss_newton_matrix(const Blocks& b, const std::vector<Cluster>& clusters, std::size_t f) {
  Dense A(f, f);
  for (const Cluster& c : clusters) {
    const Dense& J = b.J[c.block];
    for (std::size_t i = c.row0; i < c.row0 + c.rows; ++i)
      for (std::size_t p = 0; p < f; ++p)
        for (std::size_t q = 0; q < f; ++q) A(p, q) += c.weight * J(i, p) * J(i, q);
  }
  return A;
}

/// w J_kᵀ r_k of a cluster (its part of the cost's gradient).
std::vector<double> cluster_gradient(const Blocks& b, const Cluster& c) {
  const Dense& J = b.J[c.block];
  std::vector<double> g(J.cols, 0.0);
  for (std::size_t i = c.row0; i < c.row0 + c.rows; ++i)
    for (std::size_t p = 0; p < J.cols; ++p) g[p] += c.weight * J(i, p) * b.r[c.block][i];
  return g;
}

/// The cluster-robust (sandwich) standard errors, physical units (fit.h); NaN where not
/// computable. Fills the clustered correlation of `result`.
std::vector<double> clustered_errors(const Blocks& b, const std::vector<Cluster>& clusters,
                                     const std::vector<FitParameter>& params, const FreeParameters& free,
                                     FitResult& result, const std::function<void(const std::string&)>& log) {
  std::vector<double> se(params.size(), std::numeric_limits<double>::quiet_NaN());
  const std::size_t f = free.index.size();
  const auto G = static_cast<double>(clusters.size());
  if (f == 0 || clusters.size() < 2) return se;
  const std::optional<Dense> Ainv = inverse(gauss_newton_matrix(b, clusters, f));
  if (!Ainv) {
    log("clustered errors: not computable (rank-deficient Jacobian)");
    return se;
  }
  Dense B(f, f);
  for (const Cluster& c : clusters) {
    const std::vector<double> g = cluster_gradient(b, c);
    for (std::size_t p = 0; p < f; ++p)
      for (std::size_t q = 0; q < f; ++q) B(p, q) += g[p] * g[q];
  }
  const Dense V = multiply(multiply(*Ainv, B), *Ainv);
  const double small_sample = G / (G - 1.0);  // CR1: the sandwich of few clusters is low
  result.correlation_clustered.assign(f, std::vector<double>(f, 0.0));
  for (std::size_t a = 0; a < f; ++a) {
    se[free.index[a]] = std::sqrt(std::max(0.0, small_sample * V(a, a))) * params[free.index[a]].scale;
    for (std::size_t c = 0; c < f; ++c) {
      const double d = std::sqrt(std::max(V(a, a), 0.0) * std::max(V(c, c), 0.0));
      result.correlation_clustered[a][c] = d > 0 ? V(a, c) / d : (a == c ? 1.0 : 0.0);
    }
  }
  return se;
}

/// The segmentation's bias (fit.h): every fitted photo segmented at the mid level between
/// ice and ground next to its contour, and one Gauss-Newton step of the fit to those contours
/// from the optimum. Returns estimate - (estimate from the mid-level contours) per parameter
/// (NaN where not computable); fills result.segmentation_offset_px.
std::vector<double> segmentation_bias(const ObservationSequence& obs, Evaluator& ev, const ScaledParameters& sp,
                                      const FreeParameters& free, const FitOptions& o,
                                      const std::vector<Cluster>& clusters, FitResult& result,
                                      const std::function<void(const std::string&)>& log) {
  const std::vector<FitParameter>& params = ev.params();
  std::vector<double> bias(params.size(), std::numeric_limits<double>::quiet_NaN());
  const std::size_t f = free.index.size();
  if (f == 0) return bias;
  std::vector<PhotoTarget> variant;
  int estimated = 0;
  for (const PhotoTarget& t : ev.targets()) {
    PhotoTarget v = t;  // the photo's own contour where no mid level is found
    double offset = 0;
    try {
      const cv::Mat image = read_image(obs.frames[static_cast<std::size_t>(t.frame)].image);
      const Segmentation used = segment_image(image, obs.segmentation, obs.roi);
      if (const auto mid = mid_level_threshold(image, obs.segmentation, used.mask, obs.roi)) {
        SegmentationSettings s = obs.segmentation;
        s.method = SegmentationSettings::Method::kGlobal;
        s.threshold = *mid;
        const Segmentation seg = segment_image(image, s, obs.roi);
        if (seg.area_px > 0 && !seg.region.empty()) {
          v = make_target(obs, t.frame, image, seg, o);
          offset = (v.area - t.area) / t.perimeter;
          ++estimated;
        }
      }
    } catch (const InputError& e) {
      log(fmt::format("segmentation bias: frame {}: {}", t.frame + 1, e.what()));
    }
    result.segmentation_offset_px.push_back(offset);
    variant.push_back(std::move(v));
  }
  if (estimated == 0) {
    log("segmentation bias: not estimated (no photo has a mid level: adaptive or background segmentation?)");
    result.segmentation_offset_px.clear();
    return bias;
  }
  auto residuals = [&](const std::vector<double>& x) {
    std::vector<std::vector<double>> out = ev.residuals_against(x, variant);
    const auto e = ev.evaluate(x);
    if (!e->volume_residuals.empty()) out.push_back(e->volume_residuals);
    return out;
  };
  const Blocks b = blocks_at(residuals, params, sp, sp.u, free, o.step_fraction);
  const std::optional<Dense> Ainv = inverse(gauss_newton_matrix(b, clusters, f));
  if (!Ainv) return bias;
  std::vector<double> g(f, 0.0);
  for (const Cluster& c : clusters) {
    const std::vector<double> gc = cluster_gradient(b, c);
    for (std::size_t p = 0; p < f; ++p) g[p] += gc[p];
  }
  // The Gauss-Newton step to the mid-level contours' optimum is -A⁻¹ g; the bias of the
  // estimate is minus that step.
  for (std::size_t a = 0; a < f; ++a) {
    double step = 0;
    for (std::size_t q = 0; q < f; ++q) step += (*Ainv)(a, q) * g[q];
    bias[free.index[a]] = step * params[free.index[a]].scale;
  }
  return bias;
}

/// A fitted model that falls into pieces while the segmentation keeps only the largest
/// component of each photo: the photos then lack the other pieces and every estimate is
/// biased towards a faster melt. One warning naming the photos and the setting.
void check_pieces(const ObservationSequence& obs, Evaluator& ev, const ScaledParameters& sp, FitResult& result,
                  const std::function<void(const std::string&)>& log) {
  if (!obs.segmentation.largest_component || ev.targets().empty()) return;
  // Pieces the segmentation would keep if it kept all: above its minimum component size.
  const std::vector<int> pieces =
      ev.rendered_pieces(sp.values(ev.params(), sp.u), std::max(obs.segmentation.min_component_px, 1.0));
  int first = -1, last = -1, most = 1;
  for (std::size_t t = 0; t < pieces.size(); ++t) {
    if (pieces[t] <= 1) continue;
    const int frame = ev.targets()[t].frame + 1;
    if (first < 0) first = frame;
    last = frame;
    most = std::max(most, pieces[t]);
  }
  if (first < 0) return;
  const std::string w = fmt::format(
      "photos {}-{}: the fitted model shows up to {} separate pieces but the segmentation keeps only the largest "
      "component of each photo (segmentation.largest_component: true), so those photos lack the rest and the "
      "estimates are biased; set largest_component: false in the manifest",
      first, last, most);
  result.warnings.push_back(w);
  log("warning: " + w);
}

/// Two free parameters a series cannot tell apart: refused after the fit, naming them.
void check_series_identifiable(const FitResult& result) {
  const std::size_t f = result.free_names.size();
  for (const auto* corr : {&result.correlation, &result.correlation_clustered}) {
    if (corr->size() != f) continue;
    for (std::size_t a = 0; a < f; ++a)
      for (std::size_t b = a + 1; b < f; ++b)
        if (std::abs((*corr)[a][b]) > 0.995)
          throw InputError(
              fmt::format("fit: {} and {} cannot both be fitted to this mass series (correlation {:.4f}): "
                          "it shows them only together; fix one of them (--fix {}=…)",
                          result.free_names[a], result.free_names[b], (*corr)[a][b], result.free_names[b]));
  }
  if (f > 0 && result.correlation.empty())
    throw InputError(
        fmt::format("fit: the mass series cannot identify {} together (singular covariance); fix some of them",
                    fmt::join(result.free_names, ", ")));
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
  const bool series_only = !obs.has_photos();
  Targets targets;
  int start_simulations = 0;
  if (series_only) {
    check_series_parameters(obs, params, volume, o);
    start_simulations = start_time_scale(model, params, *volume, o, log);
  } else {
    targets = photo_targets(obs, o, result);
    for (const auto& s : result.frames_refused) log("refused " + s);
    if (targets.targets.empty()) throw InputError(fmt::format("{}: no usable photo to fit", obs.manifest.string()));
    // Pivot: the first photo's centroid.
    const cv::Moments mo = cv::moments(targets.first_mask, true);
    result.pivot_px = Vec2d(mo.m10 / mo.m00, mo.m01 / mo.m00);

    const bool reg_free = std::any_of(params.begin(), params.end(),
                                      [](const FitParameter& p) { return is_registration(p.name) && !p.fixed; });
    if (o.initial_registration && reg_free)
      start_registration(obs, model, params, o, targets.targets.front(), targets.first_mask, result.pivot_px, log);
  }

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
  result.simulations = ev.simulations() + start_simulations;

  // Beyond Ceres' covariance: clustered errors and the segmentation's bias (fit.h). The
  // Jacobian at the optimum was evaluated by the covariance, so this costs no simulation
  // unless the render cache has let it go.
  std::vector<double> se_clustered(params.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<double> segmentation(params.size(), std::numeric_limits<double>::quiet_NaN());
  if (!free.names.empty()) {
    const Blocks b = blocks_at([&](const std::vector<double>& x) { return evaluation_blocks(ev, x); }, params, sp, sp.u,
                               free, o.step_fraction);
    const std::vector<Cluster> clusters =
        clusters_of(b, ev.targets().size(), block_loss, series_only, o, result.readings_per_cluster);
    result.cluster_kind = series_only ? "readings" : "photo";
    result.clusters = static_cast<int>(clusters.size());
    se_clustered = clustered_errors(b, clusters, params, free, result, log);
    if (!series_only && o.segmentation_bias)
      segmentation = segmentation_bias(obs, ev, sp, free, o, clusters, result, log);
  }
  if (!series_only) check_pieces(obs, ev, sp, result, log);
  result.uncertainty_evaluations = ev.simulations() + start_simulations - result.simulations;
  result.estimates = estimates(params, sp.u, se, se_clustered, segmentation);
  if (series_only) {
    result.volume_fitted_m3 = ev.evaluate(sp.values(params, sp.u))->volume_model;
    check_series_identifiable(result);
  }
  result.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace meltlab::verify
