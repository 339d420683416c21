#include <meltlab/core/time.h>

#include <gtest/gtest.h>

#include <regex>

namespace meltlab {
namespace {

using std::chrono::system_clock;

system_clock::time_point at_unix_seconds(long long s) { return system_clock::time_point(std::chrono::seconds(s)); }

TEST(UtcTimestamp, FormatsTheEpoch) { EXPECT_EQ(utc_timestamp_iso8601(at_unix_seconds(0)), "1970-01-01T00:00:00Z"); }

TEST(UtcTimestamp, FormatsAKnownInstantInUtc) {
  // 2024-02-29T23:59:59Z, a leap day, whatever the local time zone.
  EXPECT_EQ(utc_timestamp_iso8601(at_unix_seconds(1709251199)), "2024-02-29T23:59:59Z");
}

TEST(UtcTimestamp, DropsTheFractionOfASecond) {
  const auto t = at_unix_seconds(1709251199) + std::chrono::milliseconds(999);
  EXPECT_EQ(utc_timestamp_iso8601(t), "2024-02-29T23:59:59Z");
}

TEST(UtcTimestamp, NowHasTheShape) {
  EXPECT_TRUE(std::regex_match(utc_timestamp_iso8601_now(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
}

}  // namespace
}  // namespace meltlab
