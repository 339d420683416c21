// read_time_series: valid files in several units, and every kind of bad file.

#include <meltlab/core/error.h>
#include <meltlab/verify/observations.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.h"

namespace meltlab::verify {
namespace {

using ::testing::HasSubstr;

std::string error_of(const std::filesystem::path& file) {
  try {
    read_time_series(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(TimeSeries, ReadsGrams) {
  test::TempDir dir;
  test::write_file(dir / "m.csv", "time_s,mass_g\n0,120.5\n40, 118.25\n80,115\n");
  const TimeSeries ts = read_time_series(dir / "m.csv");
  EXPECT_EQ(ts.quantity, "mass_g");
  ASSERT_EQ(ts.time_s.size(), 3U);
  EXPECT_DOUBLE_EQ(ts.time_s[1], 40);
  EXPECT_DOUBLE_EQ(ts.value[1], 118.25);
  EXPECT_DOUBLE_EQ(ts.value[2], 115);
}

TEST(TimeSeries, ReadsKilogramsInAnyColumnOrderWithCrlfAndComments) {
  test::TempDir dir;
  test::write_file(dir / "m.csv", "\xEF\xBB\xBF# scale log\r\nmass_kg , time_s\r\n0.5,0\r\n\r\n0.45,1e2\r\n");
  const TimeSeries ts = read_time_series(dir / "m.csv");
  EXPECT_EQ(ts.quantity, "mass_kg");
  ASSERT_EQ(ts.time_s.size(), 2U);
  EXPECT_DOUBLE_EQ(ts.time_s[1], 100);
  EXPECT_DOUBLE_EQ(ts.value[0], 0.5);
  EXPECT_DOUBLE_EQ(ts.value[1], 0.45);
}

TEST(TimeSeries, ReadsVolumes) {
  test::TempDir dir;
  test::write_file(dir / "v.csv", "time_s,volume_cm3\n0,10\n1,9\n");
  EXPECT_EQ(read_time_series(dir / "v.csv").quantity, "volume_cm3");
  test::write_file(dir / "w.csv", "time_s,volume_m3\n0,1e-5\n");
  EXPECT_EQ(read_time_series(dir / "w.csv").quantity, "volume_m3");
}

struct BadCase {
  const char* name;
  const char* text;
  const char* line;     // expected "<file>:<line>"
  const char* problem;  // expected substring
};

TEST(TimeSeries, BadFilesNameFileAndLine) {
  const BadCase cases[] = {
      {"bad_cell", "time_s,mass_g\n0,1\n1,abc\n", ":3:", "abc"},
      {"nan", "time_s,mass_g\n0,1\n1,nan\n", ":3:", "finite"},
      {"inf", "time_s,mass_g\n0,inf\n", ":2:", "finite"},
      {"decreasing", "time_s,mass_g\n0,1\n5,1\n4,1\n", ":4:", "does not increase"},
      {"repeated_time", "time_s,mass_g\n0,1\n0,1\n", ":3:", "does not increase"},
      {"missing_value_column", "time_s\n0\n", ":1:", "quantity"},
      {"missing_time_column", "mass_g\n1\n", ":1:", "time_s"},
      {"extra_column", "time_s,mass_g,temperature\n0,1,2\n", ":1:", "temperature"},
      {"two_quantities", "time_s,mass_g,mass_kg\n0,1,2\n", ":1:", "mass_kg"},
      {"empty_cell", "time_s,mass_g\n0,\n", ":2:", "empty cell"},
      {"missing_cell", "time_s,mass_g\n0,1\n1\n", ":3:", "cells"},
      {"trailing_junk", "time_s,mass_g\n0,1x\n", ":2:", "1x"},
      {"empty", "", ": ", "file is empty"},  // 0 bytes: no line to name
      {"header_only", "time_s,mass_g\n", ":1:", "no data"},
  };
  test::TempDir dir;
  for (const BadCase& c : cases) {
    const auto file = dir / (std::string(c.name) + ".csv");
    test::write_file(file, c.text);
    const std::string msg = error_of(file);
    EXPECT_THAT(msg, HasSubstr(file.string() + c.line)) << c.name;
    EXPECT_THAT(msg, HasSubstr(c.problem)) << c.name;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << c.name;
  }
}

TEST(TimeSeries, MissingFileAndDirectory) {
  test::TempDir dir;
  EXPECT_THAT(error_of(dir / "nope.csv"), HasSubstr("nope.csv: no such file"));
  EXPECT_THAT(error_of(dir.path()), HasSubstr("directory"));
}

}  // namespace
}  // namespace meltlab::verify
