// Fuzz target: a kl grid file ("meltlab-kl-grid 1", dims, origin, spacing, values).
#include "fuzz_support.h"

#include <meltlab/sim/kl_field.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("kl.grid", data, size);
  return meltlab::fuzz::expect_only_input_errors("kl_grid", [&] {
    auto grid = meltlab::sim::read_kl_grid(path);
    const auto field = meltlab::sim::make_grid_kl(std::move(grid), path.string());
    (void)field->value(meltlab::sim::Vec3<double>(0.5, 0.5, 0.5));
  });
}
