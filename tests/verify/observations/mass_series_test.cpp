// Weighing experiments (verify/mass_series.h): the melt checks on good and bad series, the
// comparison of curves with known answers, and the chart.

#include <meltlab/core/error.h>
#include <meltlab/verify/mass_series.h>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <sstream>

#include "test_util.h"

namespace meltlab::verify {
namespace {

using ::testing::HasSubstr;

/// A smooth melt from 250 g: m(t) = 250 (1 - t / 6000)^2, every 60 s for 100 min.
std::vector<std::pair<double, double>> melt(double noise_g = 0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<std::pair<double, double>> rows;
  for (int k = 0; k <= 100; ++k) {
    const double t = 60.0 * k;
    const double f = 1.0 - t / 6000.0;
    rows.emplace_back(t, 250.0 * f * f + (k > 0 ? noise_g * n(rng) : 0.0));
  }
  return rows;
}

std::string csv(const std::vector<std::pair<double, double>>& rows, const std::string& column = "mass_g") {
  std::ostringstream out;
  out << "time_s," << column << "\n";
  for (const auto& [t, m] : rows) out << fmt::format("{},{:.6f}\n", t, m);
  return out.str();
}

MeltSeries check(const std::string& text, test::TempDir& dir) {
  test::write_file(dir / "s.csv", text);
  return check_melt_series(read_time_series(dir / "s.csv"));
}

std::string error_of(const std::string& text) {
  test::TempDir dir;
  try {
    check(text, dir);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(MeltSeries, AGoodSeriesPassesWithItsNoise) {
  test::TempDir dir;
  constexpr double kSigma = 0.5;
  const MeltSeries s = check(csv(melt(kSigma)), dir);
  EXPECT_EQ(s.rows, 101);
  EXPECT_EQ(s.time_s.size(), 101U);
  EXPECT_TRUE(s.left_out.empty()) << s.left_out.front();
  EXPECT_EQ(s.line.front(), 2);
  EXPECT_DOUBLE_EQ(s.initial_g(), 250.0);
  // The robust sigma of 99 interior readings: within 25 % of the truth (the MAD's relative
  // spread at n = 99 is about 0.78 / sqrt(99) = 8 %; the curvature adds < 0.01 g).
  EXPECT_NEAR(s.noise_g, kSigma, 0.25 * kSigma);
  EXPECT_NEAR(s.tolerance_g, 4 * s.noise_g, 1e-12);
}

TEST(MeltSeries, VolumesBecomeGramsOfIce) {
  test::TempDir dir;
  const MeltSeries s = check("time_s,volume_cm3\n0,100\n60,90\n120,80\n", dir);
  EXPECT_EQ(s.quantity, "volume_cm3");
  EXPECT_NEAR(s.mass_g[0], 91.7, 1e-12);  // 100 cm³ at 0.917 g/cm³
  EXPECT_NEAR(s.mass_g[2], 73.36, 1e-12);
  const MeltSeries m = check("time_s,volume_m3\n0,1e-4\n60,9e-5\n120,8e-5\n", dir);
  EXPECT_NEAR(m.mass_g[0], 91.7, 1e-9);
  const MeltSeries kg = check("time_s,mass_kg\n0,0.25\n60,0.2\n120,0.15\n", dir);
  EXPECT_DOUBLE_EQ(kg.mass_g[1], 200.0);
}

TEST(MeltSeries, AQuantisedScaleIsNotNoise) {
  // A kitchen scale in whole grams on a slow melt: steps of 1 g, and a reading that flickers
  // back up by one step. Accepted: its tolerance is at least 1.5 steps.
  test::TempDir dir;
  std::vector<std::pair<double, double>> rows;
  for (int k = 0; k <= 60; ++k) rows.emplace_back(30.0 * k, std::round(250.0 - 0.4 * k));
  rows[20].second += 1;
  const MeltSeries s = check(csv(rows), dir);
  EXPECT_TRUE(s.left_out.empty());
  EXPECT_GE(s.tolerance_g, 1.5);
}

TEST(MeltSeries, TheEndOfTheMeltIsNotASpike) {
  // 40 -> 0 g in 4 readings, then zeros: a kink, departing from one side's line only.
  test::TempDir dir;
  std::vector<std::pair<double, double>> rows;
  for (int k = 0; k <= 20; ++k) rows.emplace_back(60.0 * k, std::max(0.0, 250.0 - 15.0 * k));
  const MeltSeries s = check(csv(rows), dir);
  EXPECT_TRUE(s.left_out.empty()) << s.left_out.front();
}

TEST(MeltSeries, ASpikeIsLeftOutAndNamed) {
  test::TempDir dir;
  auto rows = melt(0.3);
  rows[40].second += 25;  // a hand on the scale
  rows[70].second -= 20;  // a glitch down
  const MeltSeries s = check(csv(rows), dir);
  ASSERT_EQ(s.left_out.size(), 2U);
  EXPECT_EQ(s.time_s.size(), 99U);
  // Rows 40 and 70 are on lines 42 and 72.
  EXPECT_THAT(s.left_out[0], HasSubstr("s.csv:42:"));
  EXPECT_THAT(s.left_out[1], HasSubstr("s.csv:72:"));
  EXPECT_THAT(s.left_out[0], HasSubstr("jumps"));
  ASSERT_EQ(s.left_out_readings.time_s.size(), 2U);
  EXPECT_DOUBLE_EQ(s.left_out_readings.time_s[0], 2400.0);
}

TEST(MeltSeries, BadSeriesAreRefusedNamingTheLine) {
  // One row, two rows (nothing to fit a rate to).
  EXPECT_THAT(error_of("time_s,mass_g\n0,250\n"), HasSubstr("1 reading: a melt series needs at least 3"));
  EXPECT_THAT(error_of("time_s,mass_g\n0,250\n60,240\n"), HasSubstr("2 readings"));
  // NaN and time going back: refused by the reader, with the line.
  EXPECT_THAT(error_of("time_s,mass_g\n0,250\n60,nan\n120,230\n"), HasSubstr("s.csv:3:"));
  EXPECT_THAT(error_of("time_s,mass_g\n0,250\n60,240\n30,230\n"), HasSubstr("s.csv:4: time_s 30 does not increase"));
  // Time before the start, no ice at the start.
  EXPECT_THAT(error_of("time_s,mass_g\n-60,250\n0,240\n60,230\n"), HasSubstr("s.csv:2: time_s -60 is before"));
  EXPECT_THAT(error_of("time_s,mass_g\n0,0\n60,0\n120,0\n"), HasSubstr("s.csv:2: the first reading is 0 g"));
  // Negative mass beyond the noise (a wrong tare): named. A small negative stays.
  auto rows = melt(0.2);
  rows[100].second = -30;
  EXPECT_THAT(error_of(csv(rows)), HasSubstr("s.csv:102: -30 g is below zero"));
  rows[100].second = -0.3;
  EXPECT_EQ(error_of(csv(rows)), "(no error)");
  // The mass rising and staying up (meltwater on the scale): names both lines.
  rows = melt(0.2);
  for (int k = 50; k <= 100; ++k) rows[static_cast<std::size_t>(k)].second += 40;
  EXPECT_THAT(error_of(csv(rows)), HasSubstr("s.csv:52: the mass rises to"));
  EXPECT_THAT(error_of(csv(rows)), HasSubstr("above the reading at line 51"));
  EXPECT_THAT(error_of(csv(rows)), HasSubstr("ice only loses mass"));
  // Too many spikes to leave out (more than 10 % of 101 readings).
  rows = melt(0.2);
  for (int k = 5; k < 100; k += 8) rows[static_cast<std::size_t>(k)].second += 30;
  EXPECT_THAT(error_of(csv(rows)), HasSubstr("12 of 101 readings jump away"));
  // Numbers beyond any block of ice (1e308 m³ overflows to infinite grams).
  EXPECT_THAT(error_of("time_s,volume_m3\n0,1e308\n60,1e307\n120,1e306\n"), HasSubstr("s.csv:2:"));
  // Every message is one line.
  EXPECT_EQ(error_of(csv(rows)).find('\n'), std::string::npos);
}

TEST(MassCurve, InterpolationAndLevels) {
  const MassCurve c{{0, 100, 200, 300}, {10, 8, 4, 0}};
  EXPECT_EQ(mass_at(c, 100), 8);  // a sample's own value, exactly
  EXPECT_DOUBLE_EQ(mass_at(c, 150), 6);
  EXPECT_DOUBLE_EQ(mass_at(c, -5), 10);
  EXPECT_DOUBLE_EQ(mass_at(c, 400), 0);
  EXPECT_DOUBLE_EQ(*time_to_fall_to(c, 5), 175);
  EXPECT_DOUBLE_EQ(*time_to_fall_to(c, 0), 300);
  EXPECT_FALSE(time_to_fall_to(c, -1).has_value());
}

TEST(SeriesComparison, KnownErrorsAndTimes) {
  // The model: m = 100 - t / 10 to 0 at 1000 s, sampled every 50 s and run to 1200 s.
  MassCurve model;
  for (double t = 0; t <= 1200; t += 50) {
    model.time_s.push_back(t);
    model.mass_g.push_back(std::max(0.0, 100 - t / 10));
  }
  // Readings every 100 s to 800 s: the model plus +0.5, -0.5, ... (first reading exact).
  MassCurve obs;
  for (int k = 0; k <= 8; ++k) {
    obs.time_s.push_back(100.0 * k);
    obs.mass_g.push_back(100 - 10.0 * k + (k == 0 ? 0.0 : (k % 2 ? 0.5 : -0.5)));
  }
  const SeriesComparison c = compare_series(obs, model, 100.0, 0.02, 1);
  EXPECT_EQ(c.samples, 8);
  EXPECT_NEAR(c.rmse_g, 0.5, 1e-12);
  EXPECT_NEAR(c.max_abs_error_g, 0.5, 1e-12);
  EXPECT_NEAR(c.mean_error_g, 0.0, 1e-12);
  ASSERT_TRUE(c.half_mass_time_predicted_s && c.half_mass_time_observed_s);
  EXPECT_NEAR(*c.half_mass_time_predicted_s, 500.0, 1e-9);
  // Observed: 50 g is crossed between 500 s (50.5 g) and 600 s (39.5 g): 500 + 100 * 0.5 / 11.
  EXPECT_NEAR(*c.half_mass_time_observed_s, 500 + 100 * 0.5 / 11, 1e-9);
  EXPECT_NEAR(*c.time_to_melt_predicted_s, 980.0, 1e-9);  // 2 g
  EXPECT_FALSE(c.time_to_melt_observed_s.has_value());    // the readings stop at 20.5 g
  // Scoring the first reading too: one more sample with error 0.
  EXPECT_NEAR(compare_series(obs, model, 100.0).rmse_g, std::sqrt(8 * 0.25 / 9), 1e-12);
}

TEST(MassCurve, ChartIsDrawn) {
  const MassCurve obs{{0, 600, 1200}, {250, 150, 60}}, model{{0, 600, 1200, 1800}, {250, 148, 62, 0}};
  const cv::Mat img = mass_curve_image(obs, {{"model", model}}, "test", 5, MassCurve{{900}, {200}});
  EXPECT_EQ(img.type(), CV_8UC3);
  EXPECT_GT(img.cols, 100);
  EXPECT_LT(cv::mean(img)[0], 255.0);  // something was drawn
}

}  // namespace
}  // namespace meltlab::verify
