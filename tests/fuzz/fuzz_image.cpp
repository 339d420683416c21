// Fuzz target: an image file read by the one image reader (meltlab::read_image: photos, scene
// textures and environments all go through it), in both alpha modes, and its header-only
// twin read_image_info. The first byte picks the file extension (OpenImageIO tries the plugin
// of the extension first), the rest is the file.
#include "fuzz_support.h"

#include <meltlab/core/image.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kExtensions[] = {"png", "jpg", "tif", "exr", "ppm", "bmp", "hdr", "tga"};
  const std::string ext = kExtensions[data[0] % 8];
  const auto path = meltlab::fuzz::write_input("image." + ext, data + 1, size - 1);
  meltlab::fuzz::expect_only_input_errors("image/info", [&] { (void)meltlab::read_image_info(path); });
  meltlab::fuzz::expect_only_input_errors("image/as-stored", [&] { (void)meltlab::read_image(path); });
  return meltlab::fuzz::expect_only_input_errors("image/associated", [&] {
    (void)meltlab::read_image(path, meltlab::input_limits().image_pixels, meltlab::ImageAlpha::kAssociated);
  });
}
