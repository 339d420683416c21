// Fuzz target: a kl field file (YAML with a top-level `kl:`), as `--kl FILE` reads it, and the
// field evaluated at a few points of its box.
#include "fuzz_support.h"

#include <meltlab/sim/kl_field.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("kl.yaml", data, size);
  return meltlab::fuzz::expect_only_input_errors("kl_field", [&] {
    meltlab::sim::KlContext ctx;
    ctx.bbox_min = meltlab::sim::Vec3<double>(-1, -1, 0);
    ctx.bbox_max = meltlab::sim::Vec3<double>(1, 1, 2);
    const auto field = meltlab::sim::load_kl_field(path, ctx);
    for (double t : {0.0, 0.3, 1.0}) (void)field->value(ctx.bbox_min + t * (ctx.bbox_max - ctx.bbox_min));
  });
}
