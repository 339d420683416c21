// The pieces of the Slurm executor and of `meltlab sweep` that need no cluster: the parsers of
// squeue/sacct/scontrol output (captured from Slurm 22.05), the sbatch command line, the step
// dependencies and waves of reproduce configs, sweep configs and the collection of measures.
// The whole executor on a real cluster: tests/slurm/slurm_test.sh.
#include <meltlab/experiments/reproduce.h>
#include <meltlab/experiments/slurm.h>
#include <meltlab/experiments/sweep.h>

#include <gtest/gtest.h>

#include "test_files.h"

namespace meltlab::experiments {
namespace {

using test::message_of;
using test::TempFolder;
using test::write_file;

TEST(SlurmParse, SqueueListsEveryQueuedTaskAsLive) {
  const auto s = slurm::parse_squeue("2_1|PENDING|Resources\n2_2|RUNNING|None\n3|PENDING|Dependency\n\n");
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s.at("2_1").state, "PENDING");
  EXPECT_EQ(s.at("2_1").reason, "Resources");
  EXPECT_EQ(s.at("2_2").state, "RUNNING");
  EXPECT_EQ(s.at("3").reason, "Dependency");
  for (const auto& [_, t] : s) EXPECT_TRUE(t.live);
}

TEST(SlurmParse, SacctStateIsTheFirstWord) {
  const auto s = slurm::parse_sacct("7_0|COMPLETED|0:0\n7_1|FAILED|2:0\n8|CANCELLED by 0|0:15\n9|RUNNING|0:0\n");
  EXPECT_EQ(s.at("7_0").state, "COMPLETED");
  EXPECT_FALSE(s.at("7_0").live);
  EXPECT_EQ(s.at("7_1").exit_code, "2:0");
  EXPECT_EQ(s.at("8").state, "CANCELLED");
  EXPECT_TRUE(s.at("9").live);
}

TEST(SlurmParse, ScontrolNamesArrayTasksByTheArrayId) {
  // `scontrol show job -o 2` of an array whose task 1 failed (lines shortened)
  const std::string text =
      "JobId=2 ArrayJobId=2 ArrayTaskId=2 JobName=wrap JobState=COMPLETED Reason=None ExitCode=0:0\n"
      "JobId=5 ArrayJobId=2 ArrayTaskId=1 JobName=wrap JobState=FAILED Reason=NonZeroExitCode ExitCode=1:0\n"
      "JobId=3 JobName=wrap JobState=CANCELLED Reason=DependencyNeverSatisfied ExitCode=0:0\n";
  const auto s = slurm::parse_scontrol(text);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s.at("2_2").state, "COMPLETED");
  EXPECT_EQ(s.at("2_1").state, "FAILED");
  EXPECT_EQ(s.at("2_1").exit_code, "1:0");
  EXPECT_EQ(s.at("3").reason, "DependencyNeverSatisfied");
  EXPECT_FALSE(s.at("3").live);
  EXPECT_EQ(slurm::job_of_task("2_1"), "2");
  EXPECT_EQ(slurm::job_of_task("3"), "3");
}

TEST(Slurm, SbatchArgumentsCarryResourcesDependenciesAndTheArray) {
  slurm::JobRequest r;
  r.script = "/o/e/slurm/job-1.sh";
  r.name = "meltlab-e-1";
  r.resources = {"batch", "1:00:00", 2, "4G"};
  r.array_size = 3;
  r.after_ok = {"11", "12"};
  r.log = "/o/e/slurm/logs/job-1_%a.log";
  r.workdir = "/o/e";
  r.extra_args = {"--account=x"};
  const auto a = slurm::sbatch_arguments(r);
  const std::vector<std::string> want{"--parsable",
                                      "--job-name=meltlab-e-1",
                                      "--output=/o/e/slurm/logs/job-1_%a.log",
                                      "--error=/o/e/slurm/logs/job-1_%a.log",
                                      "--chdir=/o/e",
                                      "--export=ALL",
                                      "--partition=batch",
                                      "--time=1:00:00",
                                      "--cpus-per-task=2",
                                      "--mem=4G",
                                      "--array=0-2",
                                      "--dependency=afterok:11:12",
                                      "--kill-on-invalid-dep=yes",
                                      "--account=x",
                                      "/o/e/slurm/job-1.sh"};
  EXPECT_EQ(a, want);
  EXPECT_EQ(slurm::shell_quote("a b'c"), "'a b'\\''c'");
}

TEST(Slurm, ResourcesOverrideFieldByField) {
  const SlurmResources base = default_slurm_resources();
  const SlurmResources r = base.overridden_by({"", "0:10:00", 0, ""}).overridden_by({"gpu", "", 8, ""});
  EXPECT_EQ(r.partition, "gpu");
  EXPECT_EQ(r.time, "0:10:00");
  EXPECT_EQ(r.cpus, 8);
  EXPECT_EQ(r.mem, base.mem);
}

/// Loads one reproduce config from text.
std::vector<ReproduceExperiment> load_one(const TempFolder& tmp, const std::string& yaml) {
  write_file(tmp / "configs/x.yaml", yaml);
  ReproduceOptions o;
  o.config_dirs = {tmp / "configs"};
  o.out_dir = tmp / "out";
  o.source_dir = tmp.path();
  o.self_exe = "/bin/true";
  o.quick = true;
  return load_reproduce_experiments(o);
}

TEST(ReproduceWaves, IndependentStepsShareAWaveAndReadersWait) {
  TempFolder tmp;
  write_file(tmp / "report/r.py", "# a report script\n");
  const auto e = load_one(tmp, R"(name: x
steps:
  - {name: a, meltlab: [simulate, --out, "${step}"]}
  - {name: b, meltlab: [simulate, --out, "${step}"]}
  - {name: c, meltlab: [compare, --sim, "${out}/a", --out, "${step}"]}
  - {name: d, meltlab: [mesh-info, cube], stdout: "${out}/d.json"}
  - {name: e, meltlab: [fit, "--observations=${out}/d.json", --out, "${step}"]}
  - {name: f, meltlab: [render, --out, "${step}"]}
  - {name: g, meltlab: [render, --in, "${out}/unknown.txt", --out, "${step}"]}
  - {name: r, python: [report/r.py, "${out}"]}
)")
                     .front();
  std::map<std::string, int> wave;
  for (const auto& s : e.steps) wave[s.name] = s.wave;
  EXPECT_EQ(wave.at("a"), 0);
  EXPECT_EQ(wave.at("b"), 0);
  EXPECT_EQ(wave.at("c"), 1);  // reads a's folder
  EXPECT_EQ(wave.at("d"), 0);  // its own stdout file is its output
  EXPECT_EQ(wave.at("e"), 1);  // reads d's stdout file, after '='
  EXPECT_EQ(wave.at("f"), 0);
  EXPECT_EQ(wave.at("g"), 2);  // a path under ${out} that is nobody's: after everything before it
  EXPECT_EQ(wave.at("r"), 3);  // python: after everything
  EXPECT_EQ(e.steps[2].depends_on, (std::vector<std::size_t>{0}));
}

TEST(ReproduceWaves, SlurmSectionsAreCheckedAndInherited) {
  TempFolder tmp;
  const auto e = load_one(tmp, R"(name: x
slurm: {partition: batch, time: "1:00:00"}
steps:
  - {name: a, meltlab: [simulate], slurm: {cpus: 4, mem: 8G}}
  - {name: b, meltlab: [simulate]}
)")
                     .front();
  EXPECT_EQ(e.steps[0].slurm.partition, "batch");
  EXPECT_EQ(e.steps[0].slurm.cpus, 4);
  EXPECT_EQ(e.steps[0].slurm.mem, "8G");
  EXPECT_EQ(e.steps[1].slurm.time, "1:00:00");
  EXPECT_EQ(e.steps[1].slurm.cpus, 0);
  TempFolder bad;
  EXPECT_NE(message_of([&] {
              load_one(bad, "name: x\nslurm: {mem: lots}\nsteps: [{name: a, meltlab: [x]}]\n");
            }).find("x.yaml:2: slurm: 'lots' is not a Slurm memory size"),
            std::string::npos)
      << message_of([&] { load_one(bad, "name: x\nslurm: {mem: lots}\nsteps: [{name: a, meltlab: [x]}]\n"); });
  EXPECT_NE(message_of([&] {
              load_one(bad, "name: x\nslurm: {nodes: 2}\nsteps: [{name: a, meltlab: [x]}]\n");
            }).find("unknown key 'nodes'"),
            std::string::npos);
}

TEST(Sweep, GridVariesTheFirstOptionSlowestThenTheListedPoints) {
  TempFolder tmp;
  write_file(tmp / "s.yaml", R"(name: s
command: simulate
args: [--cycles, "5"]
grid:
  --mesh: [a, b]
  --kg: [0.5, 1]
points:
  - {--kg: 2, --mesh: c}
measures:
  - {name: v, file: run.json, json: final.volume}
)");
  const Sweep s = load_sweep(tmp / "s.yaml");
  ASSERT_EQ(s.points.size(), 5u);
  EXPECT_EQ(s.options, (std::vector<std::string>{"--mesh", "--kg"}));
  const std::vector<std::pair<std::string, std::string>> p1{{"--mesh", "a"}, {"--kg", "1"}},
      p4{{"--mesh", "c"}, {"--kg", "2"}};
  EXPECT_EQ(s.points[1].values, p1);
  EXPECT_EQ(s.points[4].values, p4);  // listed in another order, put in the options' order
  EXPECT_EQ(s.points[4].name, "p004");
  EXPECT_EQ(s.x, "--kg");  // the first option whose values are all numbers

  ReproduceOptions o;
  o.out_dir = tmp / "out";
  o.source_dir = tmp.path();
  const ReproduceExperiment e = sweep_experiment(s, o);
  ASSERT_EQ(e.steps.size(), 7u);  // 5 points, collect, figures
  EXPECT_EQ(e.steps[0].args, (std::vector<std::string>{"simulate", "--cycles", "5", "--mesh", "a", "--kg", "0.5",
                                                       "--out", (tmp / "out/s/p000").string()}));
  for (std::size_t k = 0; k < 5; ++k) EXPECT_EQ(e.steps[k].wave, 0);  // one job array
  EXPECT_EQ(e.steps[5].wave, 1);
  EXPECT_EQ(e.steps[6].wave, 2);
}

TEST(Sweep, AReproduceExperimentCanBeASweep) {
  TempFolder tmp;
  write_file(tmp / "report/experiment_report.py", "# the report script\n");
  write_file(tmp / "sweeps/s.yaml", R"(name: s
command: simulate
grid: {--kg: [0.5, 1]}
measures: [{name: v, file: run.json, json: final.volume}]
slurm: {cpus: 1}
)");
  const auto e = load_one(tmp, "name: x\nslurm: {time: '0:10:00', cpus: 4}\nsweep: sweeps/s.yaml\n").front();
  ASSERT_EQ(e.steps.size(), 4u);
  EXPECT_EQ(e.steps[1].args.back(), (tmp / "out/x/p001").string());  // the experiment's folder, not the sweep's name
  EXPECT_EQ(e.steps[2].args, (std::vector<std::string>{"sweep", "--config", (tmp / "sweeps/s.yaml").string(),
                                                       "--collect", (tmp / "out/x").string()}));
  EXPECT_EQ(e.steps[0].slurm.cpus, 1);  // the sweep's resources over the experiment's
  EXPECT_EQ(e.steps[0].slurm.time, "0:10:00");
  EXPECT_EQ(e.steps[3].wave, 2);
  TempFolder both;
  write_file(both / "sweeps/s.yaml", "name: s\n");
  EXPECT_NE(message_of([&] {
              load_one(both, "name: x\nsweep: sweeps/s.yaml\nsteps: [{name: a, meltlab: [x]}]\n");
            }).find("has both 'steps' and 'sweep'"),
            std::string::npos);
}

TEST(Sweep, RefusesBadConfigsNamingTheLine) {
  TempFolder tmp;
  const auto msg = [&](const std::string& yaml) {
    write_file(tmp / "s.yaml", yaml);
    return message_of([&] { load_sweep(tmp / "s.yaml"); });
  };
  const std::string m = "measures: [{name: v, file: run.json, json: a}]\n";
  EXPECT_NE(msg("name: s\ncommand: simulate\n" + m).find("needs 'grid' or 'points'"), std::string::npos);
  EXPECT_NE(msg("name: s\ncommand: simulate\ngrid: {--out: [a]}\n" + m).find("--out is the point's folder"),
            std::string::npos);
  EXPECT_NE(msg("name: s\ncommand: simulate\ngrid: {mesh: [a]}\n" + m).find("s.yaml:3: grid: 'mesh' is not an option"),
            std::string::npos)
      << msg("name: s\ncommand: simulate\ngrid: {mesh: [a]}\n" + m);
  EXPECT_NE(msg("name: s\ncommand: simulate\npoints: [{--kg: 1}, {--cycles: 2}]\n" + m).find("point 1 sets other"),
            std::string::npos);
  EXPECT_NE(msg("name: s\ncommand: sweep\ngrid: {--kg: [1]}\n" + m).find("not a subcommand a sweep can run"),
            std::string::npos);
  EXPECT_NE(msg("name: s\ncommand: simulate\ngrid: {--kg: [1]}\nmeasures: [{name: v, file: ../x, json: a}]\n")
                .find("inside the point's folder"),
            std::string::npos);
  EXPECT_NE(msg("name: s\ncommand: simulate\ngrid: {--kg: []}\n" + m).find("non-empty list"), std::string::npos);
}

TEST(Sweep, CollectsJsonValuesAndTheLastCsvRow) {
  TempFolder tmp;
  write_file(tmp / "s.yaml", R"(name: s
command: simulate
points: [{--mesh: "a,b"}, {--mesh: c}]
measures:
  - {name: v, file: run.json, json: final.volume}
  - {name: st, file: run.json, json: status}
  - {name: n, file: run.json, json: list.1}
  - {name: tri, file: stats.csv, column: triangles}
)");
  const Sweep s = load_sweep(tmp / "s.yaml");
  for (const char* p : {"p000", "p001"}) {
    write_file(tmp / "out" / p / "run.json", R"({"final": {"volume": 0.25}, "status": "melted", "list": [1, 7]})");
    write_file(tmp / "out" / p / "stats.csv", "cycle,triangles\n0,12\n1,10\n");
  }
  collect_sweep(s, tmp / "out");
  EXPECT_EQ(test::read_file(tmp / "out/sweep.csv"),
            "point,--mesh,v,st,n,tri\np000,\"a,b\",0.25,melted,7,10\np001,c,0.25,melted,7,10\n");
  write_file(tmp / "out/p001/run.json", R"({"final": {}})");
  EXPECT_NE(message_of([&] { collect_sweep(s, tmp / "out"); }).find("p001/run.json: no 'final.volume' (measure 'v')"),
            std::string::npos);
}

}  // namespace
}  // namespace meltlab::experiments
