#pragma once
// A weighing experiment (issue 19): the mass of the ice over time (a kitchen scale), checked
// for what a melt can do; a model's curve compared with it; both drawn in one chart.
//
// The checks (check_melt_series), on the rows of a TimeSeries (read_time_series already
// refused NaN/inf, non-numbers and time that does not increase):
//   - at least 3 rows (one or two readings say nothing about a melt rate);
//   - no time before 0 (t = 0 is the state of the mesh the model starts from);
//   - the first reading is positive (ice on the scale);
//   - noise: sigma of the readings, robustly from each reading's deviation from the straight
//     line through its neighbours (median absolute deviation); the tolerance of a reading is
//     max(4 sigma, 1.5 x the scale's step (the smallest change between readings), 0.1 % of
//     the first reading), at most 5 % of the first reading;
//   - a reading that jumps away from the line through its kept neighbours by more than the
//     tolerance (a hand on the scale, a glitch) is left out of the fit (weight 0) and listed
//     with its file:line; more than 10 % such readings (at least 2) refuse the series;
//   - a reading below -tolerance (a wrong tare) refuses the series, naming its line; small
//     negatives are noise of a tared scale and kept;
//   - a reading that rises above an earlier kept reading by more than the tolerance refuses
//     the series (ice only loses mass: is the meltwater weighed too?), naming both lines.
// Volumes are turned into masses with the density of ice (kIceDensity, 917 kg/m³ at 0 °C).

#include <meltlab/sim/physics/enthalpy.h>
#include <meltlab/verify/observations.h>

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::verify {

/// The density that turns a volume series into masses (and a mass into the mesh's volume).
inline constexpr double kIceDensity = sim::physics::constants::kIceDensity;

struct MeltSeriesOptions {
  double density_kg_m3 = kIceDensity;
  double max_outlier_fraction = 0.1;  ///< more readings left out than this refuse the series
};

/// A curve of mass over time (strictly increasing times).
struct MassCurve {
  std::vector<double> time_s, mass_g;
};

/// The rows of a series that a fit or a comparison uses, in grams.
struct MeltSeries {
  std::filesystem::path file;
  std::string quantity;  ///< the file's column: mass_g, mass_kg, volume_m3 or volume_cm3
  double density_kg_m3 = kIceDensity;
  std::vector<double> time_s, mass_g;  ///< the readings used
  std::vector<int> line;               ///< their lines in the file
  std::vector<std::string> left_out;   ///< "file:line: t = … s, … g: why" for readings left out
  MassCurve left_out_readings;         ///< the same readings, for charts
  int rows = 0;                        ///< rows in the file
  double noise_g = 0;                  ///< robust sigma of the readings
  double tolerance_g = 0;              ///< deviations within this are noise

  double initial_g() const { return mass_g.front(); }
};

/// Checks a series as a melt (see the header comment) and converts it to grams. Throws
/// InputError "file:line: problem" for a series that cannot be a melt.
MeltSeries check_melt_series(const TimeSeries& series, const MeltSeriesOptions& options = {});

/// The readings used, as a curve.
MassCurve mass_curve(const MeltSeries& series);

/// The value of a curve at `t` by linear interpolation (exactly a sample's value at its own
/// time); the end values outside its range.
double mass_at(const MassCurve& curve, double t_s);

/// The first time a curve falls to `level_g` (linear between samples), if it does.
std::optional<double> time_to_fall_to(const MassCurve& curve, double level_g);

/// A model's curve against observed readings: the errors at the observed times, and the
/// times at which each falls to half and to `melted_fraction` of the initial mass.
struct SeriesComparison {
  int samples = 0;
  double rmse_g = 0, max_abs_error_g = 0, mean_error_g = 0;  ///< predicted - observed
  double max_error_time_s = 0;
  double initial_g = 0;
  double melted_fraction = 0.02;
  std::optional<double> half_mass_time_observed_s, half_mass_time_predicted_s;
  std::optional<double> time_to_melt_observed_s, time_to_melt_predicted_s;
  std::vector<double> predicted_at_observed_g;  ///< the model at every observed time
};

/// `predicted` must cover the observed times (it may run longer: its time to melt is then
/// found even when the readings stop earlier). `initial_g` is the mass at t = 0. The errors
/// count the readings from `first_scored` on (1 when the model was scaled to the first
/// reading, whose error is then 0 by construction); the times use every reading.
SeriesComparison compare_series(const MassCurve& observed, const MassCurve& predicted, double initial_g,
                                double melted_fraction = 0.02, std::size_t first_scored = 0);

/// Observed readings (dots) and one or more model curves (lines) against time in minutes,
/// with the level of `melted_fraction` dashed (CV_8UC3, drawn with OpenCV). `left_out`
/// readings are drawn hollow.
struct LabelledCurve {
  std::string label;
  MassCurve curve;
};
cv::Mat mass_curve_image(const MassCurve& observed, const std::vector<LabelledCurve>& models, const std::string& title,
                         double melted_level_g, const MassCurve& left_out = {});

}  // namespace meltlab::verify
