// Fuzz target: an observation manifest (YAML; MELTLAB_FUZZ_MANIFEST_EXT yaml or json) as
// `meltlab compare/fit --observations FILE` reads it: keys, camera, frames, segmentation,
// time series references.
#include "fuzz_support.h"

#include <meltlab/verify/observations.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("manifest." MELTLAB_FUZZ_MANIFEST_EXT, data, size);
  return meltlab::fuzz::expect_only_input_errors("manifest", [&] {
    const auto obs = meltlab::verify::load_observations(path);
    (void)obs;
  });
}
