#pragma once
// Internals shared by the observation files (image_io.cpp, segmentation.cpp,
// observations.cpp). Not part of the public API.

#include <meltlab/verify/observations.h>

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

namespace meltlab::verify::detail {

/// Width x height of an image from its header only (meltlab::read_image_info). Throws InputError
/// "<file>: <problem>" like read_image for missing, empty, unrecognised or 0-size images.
cv::Size read_image_size(const std::filesystem::path& file);

/// Empty if `s` is usable, else the first problem as "<field>: <problem>" (the field is
/// named as in SegmentationSettings and in the manifest's `segmentation` section).
/// Does not look at the background file (only that one is named for kBackground).
std::string segmentation_settings_problem(const SegmentationSettings& s);

/// True if `channel` is one of gray, value, lightness, max, red, green, blue.
bool known_channel(const std::string& channel);

}  // namespace meltlab::verify::detail
