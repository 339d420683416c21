// Fuzz target: a mesh file of one format (MELTLAB_FUZZ_MESH_EXT: off, ply, obj, stl) read,
// welded, triangulated and validated as `meltlab simulate --mesh FILE` does.
#include "fuzz_support.h"

#include <meltlab/sim/mesh_io.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("input." MELTLAB_FUZZ_MESH_EXT, data, size);
  return meltlab::fuzz::expect_only_input_errors("mesh." MELTLAB_FUZZ_MESH_EXT, [&] {
    const auto loaded = meltlab::sim::load_mesh(path);
    (void)loaded;
  });
}
