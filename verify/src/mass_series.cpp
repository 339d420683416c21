// Weighing experiments: the melt checks, the comparison of curves and the chart
// (mass_series.h).

#include <meltlab/core/statistics.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/mass_series.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace meltlab::verify {

namespace {

/// Grams per unit of the file's quantity.
double grams_per_unit(const std::string& quantity, double density_kg_m3) {
  if (quantity == "mass_g") return 1.0;
  if (quantity == "mass_kg") return 1000.0;
  if (quantity == "volume_m3") return density_kg_m3 * 1000.0;
  if (quantity == "volume_cm3") return density_kg_m3 * 1e-3;
  throw InvariantError(fmt::format("mass series: unknown quantity '{}'", quantity));
}

/// The deviation of reading i from the straight line through readings a and b (any order of
/// times), divided by its standard deviation in units of the readings' sigma: a reading and
/// the line through two others, all with independent noise sigma, differ with variance
/// sigma² (1 + wa² + wb²), wa and wb the line's weights at t_i.
double line_deviation(const std::vector<double>& t, const std::vector<double>& g, std::size_t i, std::size_t a,
                      std::size_t b) {
  const double wb = (t[i] - t[a]) / (t[b] - t[a]);
  const double wa = 1.0 - wb;
  return (g[i] - (wa * g[a] + wb * g[b])) / std::sqrt(1.0 + wa * wa + wb * wb);
}

}  // namespace

MassCurve mass_curve(const MeltSeries& s) { return {s.time_s, s.mass_g}; }

MeltSeries check_melt_series(const TimeSeries& ts, const MeltSeriesOptions& o) {
  const std::string file = ts.file.string();
  const std::size_t n = ts.time_s.size();
  auto at = [&](std::size_t i) { return fmt::format("{}:{}", file, i < ts.line.size() ? ts.line[i] : 0); };
  if (n < 3)
    throw InputError(fmt::format("{}: {} reading{}: a melt series needs at least 3 (time_s and the mass over the melt)",
                                 file, n, n == 1 ? "" : "s"));
  if (!(o.density_kg_m3 > 0) || !(o.max_outlier_fraction >= 0))
    throw InvariantError("check_melt_series: density and outlier fraction must be positive");
  MeltSeries s;
  s.file = ts.file;
  s.quantity = ts.quantity;
  s.density_kg_m3 = o.density_kg_m3;
  s.rows = static_cast<int>(n);
  const double unit = grams_per_unit(ts.quantity, o.density_kg_m3);
  std::vector<double> g(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (ts.time_s[i] < 0)
      throw InputError(fmt::format("{}: time_s {} is before the start (t = 0 s is the state the model starts from)",
                                   at(i), ts.time_s[i]));
    g[i] = ts.value[i] * unit;
    if (!std::isfinite(g[i]) || std::abs(g[i]) > 1e12)  // a thousand tonnes: not a block of ice
      throw InputError(fmt::format("{}: {} {} is not a mass of ice in grams this program can weigh", at(i), ts.value[i],
                                   ts.quantity));
  }
  const std::string as_mass = ts.quantity.rfind("volume", 0) == 0
                                  ? fmt::format(" (volumes as mass of ice at {} kg/m³)", o.density_kg_m3)
                                  : std::string();
  if (!(g[0] > 0))
    throw InputError(fmt::format("{}: the first reading is {:.6g} g{}: a melt series starts with ice on the scale",
                                 at(0), g[0], as_mass));
  const std::vector<double>& t = ts.time_s;

  // Noise: each interior reading against the line through its two neighbours.
  std::vector<double> z;
  for (std::size_t i = 1; i + 1 < n; ++i) z.push_back(std::abs(line_deviation(t, g, i, i - 1, i + 1)));
  s.noise_g = 1.4826 * median(z);  // MAD -> sigma for Gaussian noise
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < n; ++i)
    if (const double d = std::abs(g[i] - g[i - 1]); d > 0) step = std::min(step, d);
  if (!std::isfinite(step)) step = 0;
  // 4 sigma: a Gaussian reading passes with probability 1 - 6e-5; 1.5 steps: a scale that
  // reads in whole grams turns a slow melt into steps of 1 g, up and down; 0.1 % of the
  // first reading: the floor of a noiseless (computed) series. At most 5 % of the first
  // reading: a few readings of a fast melt bend more than they scatter, and no scale is
  // that noisy.
  s.tolerance_g = std::min(std::max({4.0 * s.noise_g, 1.5 * step, 1e-3 * g[0]}), 0.05 * g[0]);
  const double tol = s.tolerance_g;

  for (std::size_t i = 0; i < n; ++i)
    if (g[i] < -tol)
      throw InputError(
          fmt::format("{}: {:.6g} g{} is below zero by more than the noise of the readings (±{:.3g} g): a "
                      "wrong tare?",
                      at(i), g[i], as_mass, tol));

  // Readings that jump away from their neighbours: from the line through the nearest kept
  // neighbours on both sides, and (where there are two) from the lines through the two
  // nearest on each side, all in the same direction. A kink (the end of the melt) departs
  // from one side's line only, so it stays. The first and last readings stay (the first is
  // the initial mass).
  std::vector<bool> kept(n, true);
  auto spike = [&](std::size_t i) -> double {
    std::vector<std::size_t> left, right;
    for (std::size_t j = i; j-- > 0 && left.size() < 2;)
      if (kept[j]) left.push_back(j);
    for (std::size_t j = i + 1; j < n && right.size() < 2; ++j)
      if (kept[j]) right.push_back(j);
    if (left.empty() || right.empty()) return 0.0;
    const double mid = line_deviation(t, g, i, left[0], right[0]);
    double d = mid;
    for (const auto* side : {&left, &right}) {
      if (side->size() < 2) continue;
      const double e = line_deviation(t, g, i, (*side)[0], (*side)[1]);
      if (e * mid <= 0) return 0.0;
      d = std::abs(e) < std::abs(d) ? e : d;
    }
    return d;
  };
  int dropped = 0;
  std::size_t first_dropped = n;
  while (true) {
    double worst = 0;
    std::size_t worst_i = 0;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      if (!kept[i]) continue;
      const double d = std::abs(spike(i));
      if (d > worst) worst = d, worst_i = i;
    }
    if (worst <= tol) break;
    kept[worst_i] = false;
    ++dropped;
    first_dropped = std::min(first_dropped, worst_i);
  }
  const int allowed = std::max(1, static_cast<int>(std::floor(o.max_outlier_fraction * static_cast<double>(n))));
  if (dropped > allowed)
    throw InputError(
        fmt::format("{}: {} of {} readings jump away from their neighbours by more than the noise (±{:.3g} "
                    "g), the first at line {}: too many to leave out (at most {})",
                    file, dropped, n, tol, ts.line.empty() ? 0 : ts.line[first_dropped], allowed));

  // Ice only loses mass: a kept reading above an earlier kept one by more than the noise.
  std::size_t lowest = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!kept[i]) continue;
    if (g[i] > g[lowest] + tol)
      throw InputError(
          fmt::format("{}: the mass rises to {:.6g} g, {:.3g} g above the reading at line {} (noise ±{:.3g} "
                      "g){}: ice only loses mass (is the meltwater weighed too?)",
                      at(i), g[i], g[i] - g[lowest], ts.line.empty() ? 0 : ts.line[lowest], tol, as_mass));
    if (g[i] < g[lowest]) lowest = i;
  }

  for (std::size_t i = 0; i < n; ++i) {
    if (kept[i]) {
      s.time_s.push_back(t[i]);
      s.mass_g.push_back(g[i]);
      s.line.push_back(i < ts.line.size() ? ts.line[i] : 0);
    } else {
      s.left_out.push_back(fmt::format("{}: t = {} s, {:.6g} g: jumps {:+.3g} g from its neighbours (noise ±{:.3g} g)",
                                       at(i), t[i], g[i], spike(i), tol));
      s.left_out_readings.time_s.push_back(t[i]);
      s.left_out_readings.mass_g.push_back(g[i]);
    }
  }
  return s;
}

double mass_at(const MassCurve& c, double t) {
  if (c.time_s.empty()) throw InvariantError("mass_at: empty curve");
  if (t <= c.time_s.front()) return c.mass_g.front();
  if (t >= c.time_s.back()) return c.mass_g.back();
  const auto it = std::lower_bound(c.time_s.begin(), c.time_s.end(), t);
  const auto j = static_cast<std::size_t>(it - c.time_s.begin());
  if (*it == t) return c.mass_g[j];  // a sample's own time: its value, exactly
  const double w = (t - c.time_s[j - 1]) / (c.time_s[j] - c.time_s[j - 1]);
  return (1.0 - w) * c.mass_g[j - 1] + w * c.mass_g[j];
}

std::optional<double> time_to_fall_to(const MassCurve& c, double level) {
  for (std::size_t j = 0; j < c.time_s.size(); ++j) {
    if (c.mass_g[j] > level) continue;
    if (j == 0) return c.time_s[0];
    const double w = (c.mass_g[j - 1] - level) / (c.mass_g[j - 1] - c.mass_g[j]);
    return c.time_s[j - 1] + w * (c.time_s[j] - c.time_s[j - 1]);
  }
  return std::nullopt;
}

SeriesComparison compare_series(const MassCurve& observed, const MassCurve& predicted, double initial_g,
                                double melted_fraction, std::size_t first_scored) {
  if (observed.time_s.empty() || predicted.time_s.empty()) throw InvariantError("compare_series: an empty curve");
  if (predicted.time_s.back() < observed.time_s.back() || predicted.time_s.front() > observed.time_s.front())
    throw InvariantError("compare_series: the prediction does not cover the observed times");
  if (first_scored >= observed.time_s.size()) throw InvariantError("compare_series: no reading to score");
  SeriesComparison c;
  c.samples = static_cast<int>(observed.time_s.size() - first_scored);
  c.initial_g = initial_g;
  c.melted_fraction = melted_fraction;
  double sum2 = 0, sum = 0;
  for (std::size_t i = 0; i < observed.time_s.size(); ++i) {
    const double p = mass_at(predicted, observed.time_s[i]);
    c.predicted_at_observed_g.push_back(p);
    if (i < first_scored) continue;
    const double e = p - observed.mass_g[i];
    sum += e;
    sum2 += e * e;
    if (std::abs(e) > c.max_abs_error_g) c.max_abs_error_g = std::abs(e), c.max_error_time_s = observed.time_s[i];
  }
  c.rmse_g = std::sqrt(sum2 / c.samples);
  c.mean_error_g = sum / c.samples;
  c.half_mass_time_observed_s = time_to_fall_to(observed, 0.5 * initial_g);
  c.half_mass_time_predicted_s = time_to_fall_to(predicted, 0.5 * initial_g);
  c.time_to_melt_observed_s = time_to_fall_to(observed, melted_fraction * initial_g);
  c.time_to_melt_predicted_s = time_to_fall_to(predicted, melted_fraction * initial_g);
  return c;
}

cv::Mat mass_curve_image(const MassCurve& observed, const std::vector<LabelledCurve>& models, const std::string& title,
                         double melted_level_g, const MassCurve& left_out) {
  constexpr int kW = 900, kH = 520, kLeft = 80, kRight = 30, kTop = 50, kBottom = 70;
  cv::Mat img(kH, kW, CV_8UC3, cv::Scalar(255, 255, 255));
  double t_max = 0, m_max = 0;
  for (const MassCurve* c : {&observed, &left_out}) {
    for (double v : c->time_s) t_max = std::max(t_max, v);
    for (double v : c->mass_g) m_max = std::max(m_max, v);
  }
  for (const auto& m : models) {
    for (double v : m.curve.time_s) t_max = std::max(t_max, v);
    for (double v : m.curve.mass_g) m_max = std::max(m_max, v);
  }
  const double t_max_min = std::max(t_max / 60.0, 1e-3);
  // Round axis ends to 1, 2 or 5 times a power of ten.
  auto nice_step = [](double range) {
    const double raw = range / 8.0, p = std::pow(10.0, std::floor(std::log10(raw)));
    return raw <= p ? p : raw <= 2 * p ? 2 * p : raw <= 5 * p ? 5 * p : 10 * p;
  };
  const double t_step = nice_step(t_max_min), m_step = nice_step(std::max(m_max, 1e-6));
  const double t_end = std::ceil(t_max_min / t_step) * t_step, m_end = std::ceil(m_max / m_step) * m_step;
  const int pw = kW - kLeft - kRight, ph = kH - kTop - kBottom;
  auto px = [&](double t_s) { return kLeft + static_cast<int>(std::lround(t_s / 60.0 / t_end * pw)); };
  auto py = [&](double g) { return kTop + ph - static_cast<int>(std::lround(std::clamp(g / m_end, -0.05, 1.0) * ph)); };
  const cv::Scalar axis(0, 0, 0), grid(225, 225, 225), dots(40, 40, 40), melted(40, 40, 200);
  const std::vector<cv::Scalar> colours{{180, 90, 20}, {40, 140, 40}, {20, 120, 220}};
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (double m = 0; m <= m_end + 1e-9 * m_end; m += m_step) {
    cv::line(img, {kLeft, py(m)}, {kLeft + pw, py(m)}, grid, 1);
    cv::putText(img, fmt::format("{:g}", m), {10, py(m) + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  }
  for (double tm = 0; tm <= t_end + 1e-9 * t_end; tm += t_step) {
    cv::line(img, {px(tm * 60), kTop + ph}, {px(tm * 60), kTop + ph + 5}, axis, 1);
    cv::putText(img, fmt::format("{:g}", tm), {px(tm * 60) - 8, kTop + ph + 22}, font, 0.45, axis, 1, cv::LINE_AA);
  }
  cv::rectangle(img, {kLeft, kTop}, {kLeft + pw, kTop + ph}, axis, 1);
  if (melted_level_g > 0) {
    for (int x = kLeft; x < kLeft + pw; x += 16)
      cv::line(img, {x, py(melted_level_g)}, {std::min(x + 8, kLeft + pw), py(melted_level_g)}, melted, 1);
    cv::putText(img, "melted", {kLeft + pw - 70, py(melted_level_g) - 6}, font, 0.45, melted, 1, cv::LINE_AA);
  }
  // Readings first, the models' lines over them; the legend along the top of the plot.
  for (std::size_t i = 0; i < observed.time_s.size(); ++i)
    cv::circle(img, {px(observed.time_s[i]), py(observed.mass_g[i])}, 3, dots, cv::FILLED, cv::LINE_AA);
  for (std::size_t i = 0; i < left_out.time_s.size(); ++i)
    cv::circle(img, {px(left_out.time_s[i]), py(left_out.mass_g[i])}, 5, melted, 1, cv::LINE_AA);
  int legend_x = kLeft + 10;
  auto legend = [&](const std::string& text, const cv::Scalar& colour) {
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, font, 0.5, 1, &baseline);
    cv::putText(img, text, {legend_x, kTop + 18}, font, 0.5, colour, 1, cv::LINE_AA);
    legend_x += size.width + 24;
  };
  legend("observed", dots);
  for (std::size_t k = 0; k < models.size(); ++k) {
    const cv::Scalar& colour = colours[k % colours.size()];
    std::vector<cv::Point> pts;
    for (std::size_t i = 0; i < models[k].curve.time_s.size(); ++i)
      pts.push_back({px(models[k].curve.time_s[i]), py(models[k].curve.mass_g[i])});
    if (pts.size() > 1) cv::polylines(img, pts, false, colour, 2, cv::LINE_AA);
    legend(models[k].label, colour);
  }
  cv::putText(img, title, {kLeft, 30}, font, 0.6, axis, 1, cv::LINE_AA);
  cv::putText(img, "time (min)", {kLeft + pw / 2 - 40, kH - 20}, font, 0.5, axis, 1, cv::LINE_AA);
  cv::putText(img, "g", {30, kTop - 10}, font, 0.5, axis, 1, cv::LINE_AA);
  return img;
}

}  // namespace meltlab::verify
