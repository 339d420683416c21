// Fuzz target: an experiment config of `meltlab reproduce` (name, vars by mode, steps).
#include "fuzz_support.h"

#include <meltlab/experiments/reproduce.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace fs = std::filesystem;
  const fs::path dir = meltlab::fuzz::work_dir() / "configs";
  fs::create_directories(dir);
  const auto path = meltlab::fuzz::write_input("configs/experiment.yaml", data, size);
  return meltlab::fuzz::expect_only_input_errors("reproduce_config", [&] {
    meltlab::experiments::ReproduceOptions o;
    o.config_dirs = {dir};
    o.out_dir = meltlab::fuzz::work_dir() / "out";
    o.source_dir = meltlab::fuzz::work_dir();
    o.self_exe = "/bin/true";
    o.quick = (size % 2) == 0;
    const auto experiments = meltlab::experiments::load_reproduce_experiments(o);
    (void)experiments;
  });
}
