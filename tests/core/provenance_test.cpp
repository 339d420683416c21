#include <meltlab/core/provenance.h>

#include <gtest/gtest.h>

#include <thread>

namespace meltlab {
namespace {

TEST(Provenance, HasTheOneShape) {
  Provenance p;
  p.subcommand = "simulate";
  p.version = "1.2.3";
  p.git_revision = "abc123";
  p.hardware = probe_hardware();
  p.hardware.extra["tbb_default_concurrency"] = 4;
  p.command_line = {"meltlab", "simulate", "--mesh", "a b.off"};
  p.start();
  p.timings_s.emplace_back("cycles", 0.25);
  p.finish();
  const nlohmann::json j = p.to_json();
  std::vector<std::string> keys;
  for (const auto& [k, v] : j.items()) keys.push_back(k);
  EXPECT_EQ(keys, (std::vector<std::string>{"command_line", "finished_utc", "hardware", "meltlab", "started_utc",
                                            "subcommand", "timings_s"}));
  EXPECT_EQ(j["subcommand"], "simulate");
  EXPECT_EQ(j["meltlab"], (nlohmann::json{{"version", "1.2.3"}, {"git_revision", "abc123"}}));
  EXPECT_EQ(j["command_line"], (nlohmann::json{"meltlab", "simulate", "--mesh", "a b.off"}));
  EXPECT_EQ(j["hardware"]["threads"], std::thread::hardware_concurrency());
  EXPECT_TRUE(j["hardware"].contains("cpu"));
  EXPECT_TRUE(j["hardware"].contains("host"));
  EXPECT_EQ(j["hardware"]["tbb_default_concurrency"], 4);
  EXPECT_EQ(j["timings_s"]["cycles"], 0.25);
  EXPECT_GE(j["timings_s"]["total"].get<double>(), 0.0);
  EXPECT_LE(j["started_utc"].get<std::string>(), j["finished_utc"].get<std::string>());
  EXPECT_EQ(j["started_utc"].get<std::string>().size(), 20u);
}

TEST(Provenance, ProbesTheCpuModelWithoutLeadingBlanks) {
  const HardwareInfo h = probe_hardware();
  EXPECT_GT(h.threads, 0u);
  if (!h.cpu.empty()) {
    EXPECT_NE(h.cpu.front(), ' ');
    EXPECT_NE(h.cpu.front(), ':');
  }
}

}  // namespace
}  // namespace meltlab
