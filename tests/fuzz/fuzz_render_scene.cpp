// Fuzz target: a render scene file (`meltlab render --scene FILE`): camera, lights, ice, ground,
// environment, outputs.
#include "fuzz_support.h"

#include <meltlab/render/render_scene.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = meltlab::fuzz::write_input("scene.yaml", data, size);
  return meltlab::fuzz::expect_only_input_errors("render_scene", [&] {
    const auto scene = meltlab::render::load_render_scene(path.string());
    (void)scene;
  });
}
