#include <meltlab/core/provenance.h>

#include <gtest/gtest.h>

#include "test_files.h"

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
  EXPECT_EQ(keys, (std::vector<std::string>{"batch_job", "command_line", "finished_utc", "hardware", "meltlab",
                                            "started_utc", "subcommand", "timings_s"}));
  EXPECT_TRUE(j["batch_job"].is_null());
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

TEST(Provenance, BatchJobFromTheSlurmEnvironment) {
  {
    const test::ScopedEnv job("SLURM_JOB_ID", std::nullopt);
    EXPECT_TRUE(probe_batch_job().is_null());
  }
  // A task of an array job: its own job id, the array's id and its index, the node.
  const test::ScopedEnv job("SLURM_JOB_ID", std::string("125"));
  const test::ScopedEnv array("SLURM_ARRAY_JOB_ID", std::string("120"));
  const test::ScopedEnv task("SLURM_ARRAY_TASK_ID", std::string("5"));
  const test::ScopedEnv node("SLURMD_NODENAME", std::string("n01"));
  const test::ScopedEnv cluster("SLURM_CLUSTER_NAME", std::nullopt);
  const nlohmann::json j = probe_batch_job();
  EXPECT_EQ(j, (nlohmann::json{{"scheduler", "slurm"},
                               {"job_id", "125"},
                               {"array_job_id", "120"},
                               {"array_task_id", "5"},
                               {"node", "n01"},
                               {"cluster", nullptr}}));
  Provenance p;
  p.batch_job = j;
  EXPECT_EQ(p.to_json()["batch_job"], j);
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
