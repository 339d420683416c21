// Fuzz target: a mass/volume series CSV (time_s,mass_g|mass_kg|volume_m3|volume_cm3), read and
// then checked as a melt (verify/mass_series.h): both may only refuse it with an InputError.
#include "fuzz_support.h"

#include <meltlab/verify/mass_series.h>
#include <meltlab/verify/observations.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("series.csv", data, size);
  return meltlab::fuzz::expect_only_input_errors("time_series", [&] {
    const auto ts = meltlab::verify::read_time_series(path);
    const auto melt = meltlab::verify::check_melt_series(ts);
    (void)melt;
  });
}
