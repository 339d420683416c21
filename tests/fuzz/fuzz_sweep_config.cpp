// Fuzz target: a sweep config of `meltlab sweep` (grid, points, measures, slurm), read and
// expanded into the steps of the reproduce engine.
#include "fuzz_support.h"

#include <meltlab/experiments/sweep.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("sweep.yaml", data, size);
  return meltlab::fuzz::expect_only_input_errors("sweep_config", [&] {
    const meltlab::experiments::Sweep sweep = meltlab::experiments::load_sweep(path);
    meltlab::experiments::ReproduceOptions o;
    o.out_dir = meltlab::fuzz::work_dir() / "out";
    o.source_dir = meltlab::fuzz::work_dir();
    o.self_exe = "/bin/true";
    const auto experiment = meltlab::experiments::sweep_experiment(sweep, o);
    (void)experiment;
  });
}
