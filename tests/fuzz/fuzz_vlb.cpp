// Fuzz target: seed 003's VLB volume file (seven header lines, then raw samples), read and
// normalised as `volume render` does.
#include "fuzz_support.h"

#include <meltlab/render/volume/volume_io.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("v.vlb", data, size);
  return meltlab::fuzz::expect_only_input_errors("vlb", [&] {
    const auto v = meltlab::render::read_volume(path);
    (void)v.value_range();
  });
}
