// Fuzz target: a dataset catalog (datasets/catalog.yaml, or one a user points
// MELTLAB_DATASETS_DIR at).
#include "fuzz_support.h"

#include <meltlab/datasets/catalog.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("catalog.yaml", data, size);
  return meltlab::fuzz::expect_only_input_errors("catalog", [&] {
    const auto entries = meltlab::datasets::dataset_catalog(path);
    (void)entries;
  });
}
