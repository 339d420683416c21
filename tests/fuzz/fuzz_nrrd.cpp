// Fuzz target: an attached NRRD volume (header, empty line, raw or gzip samples), read and
// normalised as `volume render` does.
#include "fuzz_support.h"

#include <meltlab/render/volume/volume_io.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("v.nrrd", data, size);
  return meltlab::fuzz::expect_only_input_errors("nrrd", [&] {
    const auto v = meltlab::render::read_volume(path);
    (void)v.value_range();
  });
}
