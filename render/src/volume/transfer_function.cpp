// Seed 001's transfer functions (see volume/transfer_function.h).

#include <meltlab/render/volume/transfer_function.h>

#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace meltlab::render {

std::string TfRange::bounds_text() const {
  return fmt::format("{}{:g}, {:g}{}", lo_closed ? '[' : '(', lo, hi, hi_closed ? ']' : ')');
}

namespace {

// Whether the closed interval [a, b] meets the range r.
bool meets(const TfRange& r, double a, double b) {
  if (b < r.lo || (b == r.lo && !r.lo_closed)) return false;
  if (a > r.hi || (a == r.hi && !r.hi_closed)) return false;
  return true;
}

bool empty_range(const TfRange& r) { return r.lo > r.hi || (r.lo == r.hi && !(r.lo_closed && r.hi_closed)); }

// Whether two ranges share a value.
bool overlap(const TfRange& a, const TfRange& b) {
  if (a.hi < b.lo || b.hi < a.lo) return false;
  if (a.hi == b.lo) return a.hi_closed && b.lo_closed;
  if (b.hi == a.lo) return b.hi_closed && a.lo_closed;
  return true;
}

}  // namespace

TransferFunction::TransferFunction(std::vector<TfRange> ranges, std::string name, const std::string& what)
    : ranges_(std::move(ranges)), name_(std::move(name)) {
  for (const auto& r : ranges_) {
    if (!std::isfinite(r.lo) || !std::isfinite(r.hi))
      throw InputError(fmt::format("{}: range bounds must be finite", what));
    if (empty_range(r)) throw InputError(fmt::format("{}: the range {} is empty", what, r.bounds_text()));
    if (!(r.alpha >= 0 && r.alpha <= 1))
      throw InputError(fmt::format("{}: alpha of {} must be in [0, 1] (got {})", what, r.bounds_text(), r.alpha));
    if (!r.rgb.allFinite() || (r.rgb.array() < 0).any() || (r.rgb.array() > 255).any())
      throw InputError(fmt::format("{}: the colour of {} must be in [0, 255]", what, r.bounds_text()));
  }
  std::sort(ranges_.begin(), ranges_.end(), [](const TfRange& a, const TfRange& b) {
    return a.lo < b.lo || (a.lo == b.lo && a.lo_closed && !b.lo_closed);
  });
  for (std::size_t i = 0; i + 1 < ranges_.size(); ++i)
    if (overlap(ranges_[i], ranges_[i + 1]))
      throw InputError(fmt::format("{}: the ranges {} and {} overlap", what, ranges_[i].bounds_text(),
                                   ranges_[i + 1].bounds_text()));
}

TransferFunction TransferFunction::shapes() {
  std::vector<TfRange> r(3);
  r[0] = {85, 95, false, true, Eigen::Vector3d(255, 30, 60), 0.02};
  r[1] = {95, 100, false, true, Eigen::Vector3d(10, 60, 180), 0.3};
  r[2] = {100, 115, false, false, Eigen::Vector3d(90, 210, 20), 0.6};
  return TransferFunction(r, "shapes");
}

TransferFunction TransferFunction::skull() {
  std::vector<TfRange> r(1);
  r[0] = {40, 240, false, false, Eigen::Vector3d(255, 255, 255), 1.0};
  return TransferFunction(r, "skull");
}

TransferFunction TransferFunction::named(const std::string& name, const std::string& what) {
  if (name == "shapes") return shapes();
  if (name == "skull") return skull();
  throw InputError(fmt::format("{}: unknown transfer function '{}' (shapes, skull, or a list of ranges)", what, name));
}

double TfCurve::at(double x) const {
  if (points.empty()) return 0;
  if (!(x > points.front().x())) return points.front().y();  // NaN reads the first value
  if (x >= points.back().x()) return points.back().y();
  const auto it =
      std::upper_bound(points.begin(), points.end(), x, [](double v, const Eigen::Vector2d& p) { return v < p.x(); });
  const Eigen::Vector2d& b = *it;
  const Eigen::Vector2d& a = *(it - 1);
  const double t = (x - a.x()) / (b.x() - a.x());
  return a.y() + t * (b.y() - a.y());
}

double TfCurve::max_in(double lo, double hi) const {
  double m = std::max(at(lo), at(hi));  // linear pieces: the extremes are at the ends or at points
  for (const auto& p : points)
    if (p.x() > lo && p.x() < hi) m = std::max(m, p.y());
  return m;
}

TransferFunction TransferFunction::piecewise_linear(const std::array<TfCurve, 4>& rgba, std::string name,
                                                    const std::string& what) {
  static const char* channel[4] = {"r", "g", "b", "a"};
  for (int c = 0; c < 4; ++c) {
    const auto& pts = rgba[std::size_t(c)].points;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (!pts[i].allFinite())
        throw InputError(fmt::format("{}: channel {}: control point {} is not finite", what, channel[c], i + 1));
      if (!(pts[i].y() >= 0 && pts[i].y() <= 1))
        throw InputError(fmt::format("{}: channel {}: control point {} has y = {} outside [0, 1]", what, channel[c],
                                     i + 1, pts[i].y()));
      if (i > 0 && !(pts[i].x() > pts[i - 1].x()))
        throw InputError(fmt::format("{}: channel {}: control point x must increase strictly ({} after {})", what,
                                     channel[c], pts[i].x(), pts[i - 1].x()));
    }
  }
  TransferFunction tf;
  tf.kind_ = TfKind::kPiecewiseLinear;
  tf.curves_ = rgba;
  tf.name_ = std::move(name);
  return tf;
}

TfValue TransferFunction::evaluate(double v) const {
  TfValue out;
  if (kind_ == TfKind::kPiecewiseLinear) {
    out.rgb = Eigen::Vector3d(curves_[0].at(v), curves_[1].at(v), curves_[2].at(v));
    out.alpha = curves_[3].at(v);
    return out;
  }
  const int i = find(v);
  if (i < 0) return out;
  out.rgb = ranges_[std::size_t(i)].rgb / 255.0;
  out.alpha = ranges_[std::size_t(i)].alpha;
  return out;
}

double TransferFunction::alpha_at(double v) const {
  if (kind_ == TfKind::kPiecewiseLinear) return curves_[3].at(v);
  const int i = find(v);
  return i < 0 ? 0.0 : ranges_[std::size_t(i)].alpha;
}

int TransferFunction::find(double v) const {
  for (std::size_t i = 0; i < ranges_.size(); ++i)
    if (ranges_[i].contains(v)) return int(i);
  return -1;
}

bool TransferFunction::visible_at(double v) const {
  if (kind_ == TfKind::kPiecewiseLinear) return curves_[3].at(v) > 0;
  const int i = find(v);
  return i >= 0 && ranges_[std::size_t(i)].alpha > 0;
}

bool TransferFunction::visible_in(double lo, double hi) const {
  if (kind_ == TfKind::kPiecewiseLinear) return curves_[3].max_in(lo, hi) > 0;
  for (const auto& r : ranges_)
    if (r.alpha > 0 && meets(r, lo, hi)) return true;
  return false;
}

void parse_tf_bounds(const std::string& text, TfRange& r, const std::string& what) {
  auto bad = [&] { throw InputError(fmt::format("{}: '{}' is not a value range like \"(85, 95]\"", what, text)); };
  std::string t;
  for (char c : text)
    if (!std::isspace(static_cast<unsigned char>(c))) t += c;
  if (t.size() < 5) bad();
  const char open = t.front(), close = t.back();
  if ((open != '(' && open != '[') || (close != ')' && close != ']')) bad();
  const std::size_t comma = t.find(',');
  if (comma == std::string::npos || t.find(',', comma + 1) != std::string::npos) bad();
  auto number = [&](const std::string& s) {
    std::size_t used = 0;
    double x = 0;
    try {
      x = std::stod(s, &used);
    } catch (const std::exception&) {
      bad();
    }
    if (used != s.size() || !std::isfinite(x)) bad();
    return x;
  };
  r.lo = number(t.substr(1, comma - 1));
  r.hi = number(t.substr(comma + 1, t.size() - comma - 2));
  r.lo_closed = open == '[';
  r.hi_closed = close == ']';
}

double corrected_opacity(double alpha, double step, double reference_step, OpacityExponent e) {
  if (alpha <= 0) return 0;
  if (alpha >= 1) return 1;
  const double x = e == OpacityExponent::kStepOverReference ? step / reference_step : reference_step / step;
  return 1.0 - std::pow(1.0 - alpha, x);
}

std::string opacity_exponent_name(OpacityExponent e) {
  return e == OpacityExponent::kStepOverReference ? "s_over_s0" : "s0_over_s";
}

}  // namespace meltlab::render
