#include <meltlab/core/error.h>
#include <meltlab/sim/quality.h>
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

namespace meltlab::verify {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

bool is_registration(const std::string& name) { return name.rfind("reg.", 0) == 0; }
bool is_model(const std::string& name) { return !is_registration(name) && name != "cycles_per_photo"; }

// ---------------------------------------------------------------- geometry helpers

struct Segment {
  Vec2d a, b;
};

std::vector<Segment> segments_of(const Region& region) {
  std::vector<Segment> s;
  auto add = [&](const std::vector<Vec2d>& loop) {
    for (std::size_t i = 0; i < loop.size(); ++i) s.push_back({loop[i], loop[(i + 1) % loop.size()]});
  };
  for (const Polygon& p : region) {
    add(p.outer);
    for (const auto& h : p.holes) add(h);
  }
  return s;
}

double point_segment_distance(const Vec2d& p, const Segment& s) {
  const Vec2d d = s.b - s.a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (s.a + t * d - p).norm();
}

/// Even-odd point-in-region over all loops (pixel coordinates).
bool inside(const Vec2d& p, const std::vector<Segment>& segs) {
  bool in = false;
  for (const Segment& s : segs) {
    if ((s.a.y() > p.y()) != (s.b.y() > p.y())) {
      const double x = s.a.x() + (p.y() - s.a.y()) * (s.b.x() - s.a.x()) / (s.b.y() - s.a.y());
      if (x > p.x()) in = !in;
    }
  }
  return in;
}

double signed_distance(const Vec2d& p, const std::vector<Segment>& segs) {
  double d = std::numeric_limits<double>::infinity();
  for (const Segment& s : segs) d = std::min(d, point_segment_distance(p, s));
  return inside(p, segs) ? -d : d;
}

/// `n` points spread evenly (by arc length) over all loops of a region.
std::vector<Vec2d> sample_contour(const std::vector<Segment>& segs, int n) {
  double total = 0;
  for (const Segment& s : segs) total += (s.b - s.a).norm();
  std::vector<Vec2d> out;
  if (total <= 0 || n <= 0) return out;
  const double step = total / n;
  double next = 0.5 * step, run = 0;
  for (const Segment& s : segs) {
    const double len = (s.b - s.a).norm();
    while (next <= run + len && static_cast<int>(out.size()) < n) {
      const double t = len > 0 ? (next - run) / len : 0;
      out.push_back(s.a + t * (s.b - s.a));
      next += step;
    }
    run += len;
  }
  while (static_cast<int>(out.size()) < n) out.push_back(segs.back().b);
  return out;
}

/// Bilinear lookup with clamping at the border.
double bilinear(const cv::Mat& f, const Vec2d& p) {
  const double x = std::clamp(p.x(), 0.0, f.cols - 1.0), y = std::clamp(p.y(), 0.0, f.rows - 1.0);
  const int x0 = std::min(static_cast<int>(x), f.cols - 2 < 0 ? 0 : f.cols - 2);
  const int y0 = std::min(static_cast<int>(y), f.rows - 2 < 0 ? 0 : f.rows - 2);
  const int x1 = std::min(x0 + 1, f.cols - 1), y1 = std::min(y0 + 1, f.rows - 1);
  const double tx = x - x0, ty = y - y0;
  const double a = f.at<float>(y0, x0), b = f.at<float>(y0, x1), c = f.at<float>(y1, x0), d = f.at<float>(y1, x1);
  return (a * (1 - tx) + b * tx) * (1 - ty) + (c * (1 - tx) + d * tx) * ty;
}

/// Signed distance (px) to the boundary of a binary mask, negative inside; the boundary is
/// taken half-way between pixel centres.
cv::Mat signed_distance_image(const cv::Mat& mask) {
  cv::Mat in = mask != 0, out = mask == 0, d_in, d_out;
  cv::distanceTransform(in, d_in, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::distanceTransform(out, d_out, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat sdf(mask.size(), CV_32FC1);
  for (int y = 0; y < mask.rows; ++y) {
    const float* di = d_in.ptr<float>(y);
    const float* dout = d_out.ptr<float>(y);
    float* s = sdf.ptr<float>(y);
    for (int x = 0; x < mask.cols; ++x) s[x] = di[x] > 0 ? 0.5F - di[x] : dout[x] - 0.5F;
  }
  return sdf;
}

// ---------------------------------------------------------------- targets and evaluation

struct PhotoTarget {
  int frame = 0;        ///< 0-based index in the sequence
  double position = 0;  ///< photo position in units of photos (time / interval, or index)
  std::vector<Segment> segs;
  std::vector<Vec2d> samples;
  double area = 0, perimeter = 0;
  cv::Rect bbox;        ///< photo pixels, with margin, clamped to the image
  cv::Mat sdf;          ///< signed distance to the photo contour, in photo pixels
  cv::Mat mask;
};

struct Evaluation {
  std::vector<std::vector<double>> frame_residuals;  ///< per target
  std::vector<double> volume_residuals;
};

class Evaluator {
 public:
  Evaluator(const ObservationSequence& obs, FitModel& model, std::vector<FitParameter> params, const FitOptions& options,
            std::vector<PhotoTarget> targets, const std::optional<VolumeSeries>& volume, Vec2d pivot)
      : obs_(obs), model_(model), params_(std::move(params)), o_(options), targets_(std::move(targets)), volume_(volume),
        pivot_(pivot) {}

  std::size_t residuals_per_frame() const { return static_cast<std::size_t>(o_.photo_samples) + 2; }
  const std::vector<PhotoTarget>& targets() const { return targets_; }
  const std::vector<FitParameter>& params() const { return params_; }
  int simulations() const { return simulations_; }

  std::map<std::string, double> values_of(const std::vector<double>& x) const {
    std::map<std::string, double> v;
    for (std::size_t j = 0; j < params_.size(); ++j) v[params_[j].name] = x[j];
    return v;
  }

  std::shared_ptr<const Evaluation> evaluate(const std::vector<double>& x) {
    if (auto it = cache_.find(x); it != cache_.end()) return it->second;
    if (cache_.size() > 1024) cache_.clear();
    auto e = std::make_shared<Evaluation>(compute(x));
    cache_[x] = e;
    return e;
  }

 private:
  /// The rendered contours (render pixel coordinates) every photo needs, for one set of
  /// model values and time scale: the expensive part (a simulation and a render per photo),
  /// shared by all registrations.
  struct Renders {
    struct Need {
      std::size_t target;
      double weight;
      Region region;
    };
    std::vector<Need> needs;
    std::vector<double> volume_model;  ///< per volume sample (blended)
  };

  std::shared_ptr<const Renders> renders(const std::map<std::string, double>& model_values, double K) {
    std::vector<double> key;
    for (const auto& [k, v] : model_values) key.push_back(v);
    key.push_back(K);
    if (auto it = render_cache_.find(key); it != render_cache_.end()) return it->second;
    if (render_cache_.size() > 64) render_cache_.clear();
    ++simulations_;
    auto r = std::make_shared<Renders>();
    // Which cycles are needed: the two neighbours of every photo's (fractional) cycle.
    struct At {
      std::size_t target;
      std::int64_t cycle;
      double weight;
    };
    std::vector<At> at;
    for (std::size_t t = 0; t < targets_.size(); ++t) {
      const double c = std::max(0.0, o_.first_cycle + targets_[t].position * K);
      const auto c0 = static_cast<std::int64_t>(std::floor(c));
      const double w = c - static_cast<double>(c0);
      at.push_back({t, c0, 1.0 - w});
      if (w > 0) at.push_back({t, c0 + 1, w});
    }
    std::vector<std::array<double, 2>> volume_weights;
    std::vector<std::array<std::int64_t, 2>> volume_cycles;
    if (volume_ && o_.volume_weight > 0) {
      const double interval = obs_.interval_s.value_or(1.0);
      for (std::size_t s = 0; s < volume_->time_s.size(); ++s) {
        const double c = std::max(0.0, o_.first_cycle + volume_->time_s[s] / interval * K);
        const auto c0 = static_cast<std::int64_t>(std::floor(c));
        volume_cycles.push_back({c0, c0 + 1});
        volume_weights.push_back({1.0 - (c - static_cast<double>(c0)), c - static_cast<double>(c0)});
      }
    }
    std::set<std::int64_t> cycles;
    for (const At& n : at) cycles.insert(n.cycle);
    for (const auto& vc : volume_cycles) cycles.insert(vc.begin(), vc.end());
    std::map<std::int64_t, double> volume_at;
    const std::unique_ptr<sim::MeshSequence> seq = model_.start(model_values);
    cv::Mat coverage;
    for (const std::int64_t cycle : cycles) {
      const sim::TriMesh<double>& mesh = seq->mesh_at(cycle);
      if (!volume_cycles.empty()) volume_at[cycle] = mesh.live_triangle_count() > 0 ? sim::mesh_volume(mesh) : 0.0;
      for (const At& n : at) {
        if (n.cycle != cycle || n.weight <= 0) continue;
        r->needs.push_back({n.target, n.weight, render_region(n.target, mesh, coverage)});
      }
    }
    for (std::size_t s = 0; s < volume_cycles.size(); ++s)
      r->volume_model.push_back(volume_weights[s][0] * volume_at[volume_cycles[s][0]] +
                                volume_weights[s][1] * volume_at[volume_cycles[s][1]]);
    render_cache_[key] = r;
    return r;
  }

  Evaluation compute(const std::vector<double>& x) {
    const std::map<std::string, double> values = values_of(x);
    std::map<std::string, double> model_values;
    for (const auto& [k, v] : values)
      if (is_model(k)) model_values[k] = v;
    const double K = values.count("cycles_per_photo") ? values.at("cycles_per_photo") : 7.0;
    const Similarity2D reg = registration_of(values, pivot_);
    const auto rs = renders(model_values, K);
    Evaluation e;
    e.frame_residuals.assign(targets_.size(), std::vector<double>(residuals_per_frame(), 0.0));
    for (const auto& n : rs->needs) {
      const std::vector<double> r = frame_residuals(targets_[n.target], transform_region(n.region, reg));
      auto& acc = e.frame_residuals[n.target];
      for (std::size_t i = 0; i < r.size(); ++i) acc[i] += n.weight * r[i];
    }
    if (!rs->volume_model.empty()) {
      const double v0 = std::max(volume_->volume_m3.front(), 1e-30);
      for (std::size_t s = 0; s < rs->volume_model.size(); ++s)
        e.volume_residuals.push_back(o_.volume_weight * (rs->volume_model[s] - volume_->volume_m3[s]) / v0);
    }
    return e;
  }

  /// The rendered contour of a photo's window (render pixel coordinates of the whole image).
  /// The window is the photo's, mapped back through the initial registration and widened by
  /// a quarter of its size, so registrations reached during the fit stay inside it.
  Region render_region(std::size_t target, const sim::TriMesh<double>& mesh, cv::Mat& coverage) {
    const PhotoTarget& t = targets_[target];
    const bool distorted = std::holds_alternative<render::Pinhole>(obs_.camera) &&
                           std::get<render::Pinhole>(obs_.camera).distorted();
    // A distorted pinhole renders the whole image, as the fit always has: its renderer
    // resamples an undistorted canvas placed by the window, so a crop would move the
    // coverage by rounding (and fit.json numbers must not change).
    render::PixelWindow window{0, 0, render::camera_width(obs_.camera), render::camera_height(obs_.camera)};
    if (!distorted) {
      const Similarity2D inv = initial_registration_.inverse();
      Vec2d lo = Vec2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
      for (const Vec2d& c : {Vec2d(t.bbox.x, t.bbox.y), Vec2d(t.bbox.x + t.bbox.width, t.bbox.y),
                             Vec2d(t.bbox.x, t.bbox.y + t.bbox.height), Vec2d(t.bbox.x + t.bbox.width, t.bbox.y + t.bbox.height)}) {
        const Vec2d q = inv.apply(c);
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
      const Vec2d widen = 0.25 * (hi - lo) + Vec2d::Constant(2.0);
      lo -= widen;
      hi += widen;
      window = render::pixel_window(obs_.camera, lo, hi);
    }
    render::SilhouetteRenderer renderer(render::crop(obs_.camera, window),
                                        render::SilhouetteOptions{std::max(2, o_.supersample), true});
    renderer.render(mesh, coverage);
    Region region = region_from_image(coverage, 0.5);
    const Vec2d offset(window.x, window.y);
    for (Polygon& p : region) {
      for (Vec2d& v : p.outer) v += offset;
      for (auto& h : p.holes)
        for (Vec2d& v : h) v += offset;
    }
    return region;
  }

  /// Residuals of one photo against a rendered contour in photo coordinates.
  std::vector<double> frame_residuals(const PhotoTarget& t, const Region& region) const {
    std::vector<double> r(residuals_per_frame(), 0.0);
    const std::vector<Segment> segs = segments_of(region);
    const std::size_t np = static_cast<std::size_t>(o_.photo_samples);
    if (segs.empty()) {
      // Nothing rendered where the photo shows ice: every photo point is about one
      // equivalent radius from the (vanished) render.
      const double radius = std::sqrt(t.area / std::numbers::pi);
      for (std::size_t i = 0; i < np; ++i) r[i] = radius;
      r[np] = -t.area / t.perimeter;
      r[np + 1] = 0;
      return r;
    }
    for (std::size_t i = 0; i < np; ++i) r[i] = signed_distance(t.samples[i], segs);
    r[np] = (region_area(region) - t.area) / t.perimeter;
    // Render contour to photo contour: RMS of the photo's signed distance over the rendered
    // contour (Simpson's rule per segment), scaled so its square weighs like N_r samples.
    double integral = 0, length = 0;
    for (const Segment& s : segs) {
      const double len = (s.b - s.a).norm();
      const double da = bilinear(t.sdf, s.a), dm = bilinear(t.sdf, 0.5 * (s.a + s.b)), db = bilinear(t.sdf, s.b);
      integral += len * (da * da + 4 * dm * dm + db * db) / 6.0;
      length += len;
    }
    r[np + 1] = length > 0 ? std::sqrt(o_.render_samples * integral / length) : 0.0;
    return r;
  }

  const ObservationSequence& obs_;
  FitModel& model_;
  std::vector<FitParameter> params_;
  FitOptions o_;
  std::vector<PhotoTarget> targets_;
  std::optional<VolumeSeries> volume_;
  Vec2d pivot_;
  std::map<std::vector<double>, std::shared_ptr<const Evaluation>> cache_;
  std::map<std::vector<double>, std::shared_ptr<const Renders>> render_cache_;
  int simulations_ = 0;
  Similarity2D initial_registration_;

 public:
  void set_initial_registration(const Similarity2D& t) { initial_registration_ = t; }
};

/// One residual block: a photo's residuals (or the volume residuals), as functions of all
/// parameters (one 1-D block each, in units of their scale), with central differences.
class BlockCost final : public ceres::CostFunction {
 public:
  BlockCost(Evaluator& ev, int target, int count, double step, std::vector<double> lower_u, std::vector<double> upper_u)
      : ev_(ev), target_(target), step_(step), lower_u_(std::move(lower_u)), upper_u_(std::move(upper_u)) {
    set_num_residuals(count);
    for (std::size_t j = 0; j < ev.params().size(); ++j) mutable_parameter_block_sizes()->push_back(1);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    // A parameter vector the model refuses (e.g. an invalid kl field) is an infeasible step.
    try {
      return evaluate(parameters, residuals, jacobians);
    } catch (const InputError&) {
      return false;
    }
  }

 private:
  bool evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
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
      for (int i = 0; i < num_residuals(); ++i) jacobians[j][i] = (rp[static_cast<std::size_t>(i)] - rm[static_cast<std::size_t>(i)]) / h;
    }
    return true;
  }

  std::vector<double> residuals_at(const std::vector<double>& u) const {
    std::vector<double> x(u.size());
    for (std::size_t j = 0; j < u.size(); ++j) x[j] = ev_.params()[j].initial + ev_.params()[j].scale * u[j];
    const auto e = ev_.evaluate(x);
    return target_ >= 0 ? e->frame_residuals[static_cast<std::size_t>(target_)] : e->volume_residuals;
  }

  Evaluator& ev_;
  int target_;
  double step_;
  std::vector<double> lower_u_, upper_u_;
};

class LogIterations final : public ceres::IterationCallback {
 public:
  LogIterations(const FitOptions& o, const Evaluator& ev) : o_(o), ev_(ev) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (o_.log)
      o_.log(fmt::format("iteration {}: cost {:.6g}, |step| {:.3g}, {} simulations", s.iteration, s.cost, s.step_norm,
                         ev_.simulations()));
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const FitOptions& o_;
  const Evaluator& ev_;
};

double huber_cost(const std::vector<double>& r, double a) {
  double s = 0;
  for (double v : r) s += v * v;
  return 0.5 * (s <= a * a ? s : 2 * a * std::sqrt(s) - a * a);
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
  return 7.0;
}

FitResult fit_sequence(const ObservationSequence& obs, FitModel& model, const std::vector<FitParameter>& parameters_in,
                       const FitOptions& o, const std::optional<VolumeSeries>& volume) {
  const auto t0 = std::chrono::steady_clock::now();
  auto log = [&](const std::string& s) {
    if (o.log) o.log(s);
  };
  std::vector<FitParameter> params = parameters_in;
  std::set<std::string> names;
  for (const FitParameter& p : params) {
    if (!names.insert(p.name).second) throw InputError(fmt::format("fit: parameter {} given twice", p.name));
    if (!(p.lower <= p.initial && p.initial <= p.upper) || !std::isfinite(p.initial))
      throw InputError(fmt::format("fit: {} = {} is outside its bounds [{}, {}]", p.name, p.initial, p.lower, p.upper));
    if (!(p.scale > 0) || !std::isfinite(p.scale)) throw InputError(fmt::format("fit: {} needs a scale > 0", p.name));
  }
  if (o.photo_samples < 4 || o.render_samples < 1) throw InputError("fit: at least 4 photo and 1 render samples per frame");

  // ---- photo targets (segmented once) ----
  FitResult result;
  std::vector<PhotoTarget> targets;
  std::vector<int> frames = o.frames;
  if (frames.empty())
    for (const Frame& f : obs.frames) frames.push_back(f.index);
  cv::Mat first_mask;
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
    t.bbox = cv::Rect(bound.x - m, bound.y - m, bound.width + 2 * m, bound.height + 2 * m) & cv::Rect(0, 0, image.cols, image.rows);
    t.sdf = signed_distance_image(seg.mask);
    if (first_mask.empty()) first_mask = seg.mask;
    targets.push_back(std::move(t));
    result.frames_used.push_back(k);
  }
  for (const auto& s : result.frames_refused) log("refused " + s);
  if (targets.empty()) throw InputError(fmt::format("{}: no usable photo to fit", obs.manifest.string()));

  // Pivot: the first photo's centroid.
  const cv::Moments mo = cv::moments(first_mask, true);
  result.pivot_px = Vec2d(mo.m10 / mo.m00, mo.m01 / mo.m00);

  auto index_of = [&](const std::string& name) -> int {
    for (std::size_t j = 0; j < params.size(); ++j)
      if (params[j].name == name) return static_cast<int>(j);
    return -1;
  };

  // ---- initial registration from the masks ----
  const bool reg_free = std::any_of(params.begin(), params.end(), [](const FitParameter& p) {
    return is_registration(p.name) && !p.fixed;
  });
  if (o.initial_registration && reg_free) {
    std::map<std::string, double> mv;
    for (const FitParameter& p : params)
      if (is_model(p.name)) mv[p.name] = p.initial;
    const int kc = index_of("cycles_per_photo");
    const double K = kc >= 0 ? params[static_cast<std::size_t>(kc)].initial : 7.0;
    auto seq = model.start(mv);
    const auto cycle = static_cast<std::int64_t>(std::llround(o.first_cycle + targets.front().position * K));
    const cv::Mat render_mask = render::silhouette_mask(seq->mesh_at(cycle), obs.camera);
    if (cv::countNonZero(render_mask) > 0) {
      const RegistrationResult rr = register_masks(first_mask, render_mask);
      // Express it about the pivot: translation' = translation - (pivot - s R pivot).
      Similarity2D about;
      about.scale = rr.render_to_photo.scale;
      about.angle_rad = rr.render_to_photo.angle_rad;
      const Vec2d base = result.pivot_px - about.apply(result.pivot_px);
      const Vec2d t = rr.render_to_photo.translation - base;
      const std::map<std::string, double> init{{"reg.tx_px", t.x()}, {"reg.ty_px", t.y()},
                                               {"reg.angle_deg", about.angle_rad / kDeg}, {"reg.scale", about.scale}};
      for (FitParameter& p : params) {
        if (!is_registration(p.name) || p.fixed) continue;
        const auto it = init.find(p.name);
        if (it != init.end()) p.initial = std::clamp(it->second, p.lower, p.upper);
      }
      log(fmt::format("initial registration ({}): P {:.4f} -> {:.4f}", rr.method, rr.P_before, rr.P_after));
    }
  }

  Evaluator ev(obs, model, params, o, std::move(targets), volume, result.pivot_px);
  {
    std::map<std::string, double> init;
    for (const FitParameter& p : params) init[p.name] = p.initial;
    ev.set_initial_registration(registration_of(init, result.pivot_px));
  }
  const std::size_t n = params.size();
  std::vector<double> u(n, 0.0), lower_u(n), upper_u(n);
  for (std::size_t j = 0; j < n; ++j) {
    lower_u[j] = (params[j].lower - params[j].initial) / params[j].scale;
    upper_u[j] = (params[j].upper - params[j].initial) / params[j].scale;
  }
  const double block_loss = o.huber_px * std::sqrt(static_cast<double>(ev.residuals_per_frame()));
  auto total_cost = [&](const std::vector<double>& uu) {
    std::vector<double> x(n);
    for (std::size_t j = 0; j < n; ++j) x[j] = params[j].initial + params[j].scale * uu[j];
    const auto e = ev.evaluate(x);
    double c = 0;
    for (const auto& r : e->frame_residuals) c += huber_cost(r, block_loss);
    for (double v : e->volume_residuals) c += 0.5 * v * v;
    return c;
  };

  // ---- coarse scan of kg (guards against a local minimum of the melt rate) ----
  const int kg = index_of("kg");
  if (kg >= 0 && !params[static_cast<std::size_t>(kg)].fixed && !o.kg_scan.empty()) {
    const auto j = static_cast<std::size_t>(kg);
    double best = std::numeric_limits<double>::infinity(), best_u = 0;
    for (const double f : o.kg_scan) {
      const double value = std::clamp(params[j].initial * f, params[j].lower, params[j].upper);
      std::vector<double> uu = u;
      uu[j] = (value - params[j].initial) / params[j].scale;
      const double c = total_cost(uu);
      result.kg_scan.emplace_back(value, c);
      log(fmt::format("scan kg = {:.4g}: cost {:.6g}", value, c));
      if (c < best) best = c, best_u = uu[j];
    }
    u[j] = best_u;
  }

  // ---- the least-squares problem ----
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  std::vector<double*> blocks;
  for (std::size_t j = 0; j < n; ++j) blocks.push_back(&u[j]);
  for (std::size_t t = 0; t < ev.targets().size(); ++t) {
    problem.AddResidualBlock(new BlockCost(ev, static_cast<int>(t), static_cast<int>(ev.residuals_per_frame()), o.step_fraction,
                                           lower_u, upper_u),
                             new ceres::HuberLoss(block_loss), blocks);
  }
  if (volume && o.volume_weight > 0 && !volume->time_s.empty())
    problem.AddResidualBlock(new BlockCost(ev, -1, static_cast<int>(volume->time_s.size()), o.step_fraction, lower_u, upper_u),
                             nullptr, blocks);
  std::vector<std::string> free_names;
  std::vector<std::size_t> free_index;
  for (std::size_t j = 0; j < n; ++j) {
    if (params[j].fixed) {
      problem.SetParameterBlockConstant(&u[j]);
      continue;
    }
    if (std::isfinite(lower_u[j])) problem.SetParameterLowerBound(&u[j], 0, lower_u[j]);
    if (std::isfinite(upper_u[j])) problem.SetParameterUpperBound(&u[j], 0, upper_u[j]);
    free_names.push_back(params[j].name);
    free_index.push_back(j);
  }
  result.initial_cost = total_cost(u);
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
  if (!free_names.empty()) ceres::Solve(so, &problem, &summary);
  result.final_cost = free_names.empty() ? result.initial_cost : summary.final_cost;
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = free_names.empty() || summary.termination_type == ceres::CONVERGENCE;
  result.message = free_names.empty() ? "nothing to fit" : summary.message;
  result.free_names = free_names;

  // ---- uncertainty: covariance of the free parameters, scaled by the residual variance ----
  std::size_t m = 0;
  {
    std::vector<double> x(n);
    for (std::size_t j = 0; j < n; ++j) x[j] = params[j].initial + params[j].scale * u[j];
    const auto e = ev.evaluate(x);
    for (const auto& r : e->frame_residuals) {
      double s = 0;
      for (double v : r) s += v * v;
      result.frame_rms_px.push_back(std::sqrt(s / static_cast<double>(r.size())));
      m += r.size();
    }
    m += e->volume_residuals.size();
  }
  const double dof = static_cast<double>(m) - static_cast<double>(free_names.size());
  result.residual_sigma_px = dof > 0 ? std::sqrt(2 * result.final_cost / dof) : 0.0;
  std::vector<double> se(n, std::numeric_limits<double>::quiet_NaN());
  if (!free_names.empty()) {
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.null_space_rank = -1;
    co.num_threads = 1;
    ceres::Covariance cov(co);
    std::vector<std::pair<const double*, const double*>> pairs;
    for (std::size_t a : free_index)
      for (std::size_t b : free_index) pairs.emplace_back(&u[a], &u[b]);
    if (cov.Compute(pairs, &problem)) {
      const std::size_t f = free_index.size();
      std::vector<std::vector<double>> c(f, std::vector<double>(f));
      for (std::size_t a = 0; a < f; ++a)
        for (std::size_t b = 0; b < f; ++b) cov.GetCovarianceBlock(&u[free_index[a]], &u[free_index[b]], &c[a][b]);
      const double var = result.residual_sigma_px * result.residual_sigma_px;
      result.correlation.assign(f, std::vector<double>(f, 0.0));
      for (std::size_t a = 0; a < f; ++a) {
        se[free_index[a]] = std::sqrt(std::max(0.0, c[a][a] * var)) * params[free_index[a]].scale;
        for (std::size_t b = 0; b < f; ++b) {
          const double d = std::sqrt(std::max(c[a][a], 0.0) * std::max(c[b][b], 0.0));
          result.correlation[a][b] = d > 0 ? c[a][b] / d : (a == b ? 1.0 : 0.0);
        }
      }
    } else {
      log("covariance: not computable (rank-deficient Jacobian)");
    }
  }
  for (std::size_t j = 0; j < n; ++j) {
    FitEstimate e;
    e.name = params[j].name;
    e.initial = params[j].initial;
    e.value = params[j].initial + params[j].scale * u[j];
    e.fixed = params[j].fixed;
    if (!e.fixed && std::isfinite(se[j])) e.standard_error = se[j];
    const double tol = 1e-9 * params[j].scale;
    e.at_bound = !e.fixed && (std::abs(e.value - params[j].lower) < tol || std::abs(e.value - params[j].upper) < tol);
    result.estimates.push_back(e);
  }
  result.simulations = ev.simulations();
  result.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace meltlab::verify
