// Fuzz target: an image file read by both image readers (photos: verify::read_image; scene
// textures: render::read_rgb_image). The first byte picks the file extension (OpenImageIO tries
// the plugin of the extension first), the rest is the file.
#include "fuzz_support.h"

#include <meltlab/render/render_assets.h>
#include <meltlab/verify/observations.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {"png", "jpg", "tif", "exr", "ppm", "bmp", "hdr", "tga"};
  const std::string ext = kExtensions[data[0] % 8];
  const auto path = meltlab::fuzz::write_input("image." + ext, data + 1, size - 1);
  meltlab::fuzz::expect_only_input_errors("image/photo", [&] { (void)meltlab::verify::read_image(path); });
  return meltlab::fuzz::expect_only_input_errors("image/texture", [&] { (void)meltlab::render::read_rgb_image(path); });
}
