// Fuzz target: a mass/volume series CSV (time_s,mass_g|mass_kg|volume_m3|volume_cm3).
#include "fuzz_support.h"

#include <meltlab/verify/observations.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("series.csv", data, size);
  return meltlab::fuzz::expect_only_input_errors("time_series", [&] {
    const auto ts = meltlab::verify::read_time_series(path);
    (void)ts;
  });
}
