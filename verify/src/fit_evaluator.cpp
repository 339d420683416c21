// The model evaluator of the fit: residuals of every photo (and the volume series) for one
// parameter vector, with the simulation + renders cached per model values and time scale.

#include "fit_detail.h"

#include <meltlab/core/error.h>
#include <meltlab/sim/quality.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

namespace meltlab::verify::fit_detail {

std::map<std::string, double> Evaluator::values_of(const std::vector<double>& x) const {
  std::map<std::string, double> v;
  for (std::size_t j = 0; j < params_.size(); ++j) v[params_[j].name] = x[j];
  return v;
}

std::shared_ptr<const Evaluation> Evaluator::evaluate(const std::vector<double>& x) {
  if (auto it = cache_.find(x); it != cache_.end()) return it->second;
  if (cache_.size() > 1024) cache_.clear();
  auto e = std::make_shared<Evaluation>(compute(x));
  cache_[x] = e;
  return e;
}

std::shared_ptr<const Evaluator::Renders> Evaluator::renders(const std::map<std::string, double>& model_values,
                                                             double K, std::optional<double> seconds_per_cycle) {
  std::vector<double> key;
  for (const auto& [k, v] : model_values) key.push_back(v);
  key.push_back(K);
  if (seconds_per_cycle) key.push_back(*seconds_per_cycle);
  if (auto it = render_cache_.find(key); it != render_cache_.end()) return it->second;
  if (render_cache_.size() > 64) render_cache_.clear();
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
      const double c = seconds_per_cycle ? std::max(0.0, o_.first_cycle + volume_->time_s[s] / *seconds_per_cycle)
                                         : std::max(0.0, o_.first_cycle + volume_->time_s[s] / interval * K);
      // An infeasible step for the solver (BlockCost returns false), an error elsewhere.
      if (!(c <= static_cast<double>(o_.max_cycles)))
        throw InputError(fmt::format("fit: the reading at {} s maps to cycle {:.4g}, beyond {} cycles",
                                     volume_->time_s[s], c, o_.max_cycles));
      const auto c0 = static_cast<std::int64_t>(std::floor(c));
      volume_cycles.push_back({c0, c0 + 1});
      volume_weights.push_back({1.0 - (c - static_cast<double>(c0)), c - static_cast<double>(c0)});
    }
  }
  std::set<std::int64_t> cycles;
  for (const At& n : at) cycles.insert(n.cycle);
  for (const auto& vc : volume_cycles) cycles.insert(vc.begin(), vc.end());
  const bool relative = !volume_cycles.empty() && volume_->initial_volume_m3.has_value();
  if (relative) cycles.insert(0);  // the mesh's own initial volume
  std::map<std::int64_t, double> volume_at;
  ++simulations_;
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
  if (relative) {
    // The mesh scaled to the initial volume of the series.
    const double v0 = volume_at[0];
    if (!(v0 > 0)) throw InputError("fit: the mesh encloses no volume at cycle 0");
    for (double& v : r->volume_model) v = v / v0 * *volume_->initial_volume_m3;
  }
  render_cache_[key] = r;
  return r;
}

std::shared_ptr<const Evaluator::Renders> Evaluator::renders_at(const std::map<std::string, double>& values) {
  std::map<std::string, double> model_values;
  for (const auto& [k, v] : values)
    if (is_model_parameter(k)) model_values[k] = v;
  const double K = values.count("cycles_per_photo") ? values.at("cycles_per_photo") : kDefaultCyclesPerPhoto;
  const std::optional<double> S =
      values.count("seconds_per_cycle") ? std::optional<double>(values.at("seconds_per_cycle")) : std::nullopt;
  return renders(model_values, K, S);
}

std::vector<std::vector<double>> Evaluator::weighted_frame_residuals(const Renders& rs,
                                                                     const std::vector<PhotoTarget>& targets,
                                                                     const Similarity2D& reg) const {
  std::vector<std::vector<double>> out(targets.size(), std::vector<double>(residuals_per_frame(), 0.0));
  for (const auto& n : rs.needs) {
    const std::vector<double> r = frame_residuals(targets[n.target], transform_region(n.region, reg));
    for (std::size_t i = 0; i < r.size(); ++i) out[n.target][i] += n.weight * r[i];
  }
  return out;
}

Evaluation Evaluator::compute(const std::vector<double>& x) {
  const std::map<std::string, double> values = values_of(x);
  const auto rs = renders_at(values);
  Evaluation e;
  e.frame_residuals = weighted_frame_residuals(*rs, targets_, registration_of(values, pivot_));
  if (!rs->volume_model.empty()) {
    const double v0 = std::max(volume_->initial_volume_m3.value_or(volume_->volume_m3.front()), 1e-30);
    for (std::size_t s = 0; s < rs->volume_model.size(); ++s)
      e.volume_residuals.push_back(o_.volume_weight * (rs->volume_model[s] - volume_->volume_m3[s]) / v0);
    e.volume_model = rs->volume_model;
  }
  return e;
}

std::vector<std::vector<double>> Evaluator::residuals_against(const std::vector<double>& x,
                                                              const std::vector<PhotoTarget>& others) {
  if (others.size() != targets_.size()) throw InvariantError("residuals_against: one target per fitted photo");
  const std::map<std::string, double> values = values_of(x);
  return weighted_frame_residuals(*renders_at(values), others, registration_of(values, pivot_));
}

std::vector<int> Evaluator::rendered_pieces(const std::vector<double>& x, double min_area_px) {
  const auto rs = renders_at(values_of(x));
  std::vector<int> pieces(targets_.size(), 0);
  std::vector<double> weight(targets_.size(), -1.0);
  for (const auto& n : rs->needs) {
    if (n.weight <= weight[n.target]) continue;
    weight[n.target] = n.weight;
    int count = 0;
    for (const Polygon& p : n.region)
      if (region_area(Region{p}) >= min_area_px) ++count;
    pieces[n.target] = count;
  }
  return pieces;
}

/// The rendered contour of a photo's window (render pixel coordinates of the whole image).

/// The window is the photo's, mapped back through the initial registration and widened by
/// a quarter of its size, so registrations reached during the fit stay inside it.
Region Evaluator::render_region(std::size_t target, const sim::TriMesh<double>& mesh, cv::Mat& coverage) {
  const PhotoTarget& t = targets_[target];
  const bool distorted =
      std::holds_alternative<render::Pinhole>(obs_.camera) && std::get<render::Pinhole>(obs_.camera).distorted();
  // A distorted pinhole renders the whole image, as the fit always has: its renderer
  // resamples an undistorted canvas placed by the window, so a crop would move the
  // coverage by rounding (and fit.json numbers must not change).
  render::PixelWindow window{0, 0, render::camera_width(obs_.camera), render::camera_height(obs_.camera)};
  if (!distorted) {
    const Similarity2D inv = initial_registration_.inverse();
    Vec2d lo = Vec2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Vec2d& c :
         {Vec2d(t.bbox.x, t.bbox.y), Vec2d(t.bbox.x + t.bbox.width, t.bbox.y),
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
std::vector<double> Evaluator::frame_residuals(const PhotoTarget& t, const Region& region) const {
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

}  // namespace meltlab::verify::fit_detail
