#pragma once
// Seed 003's post-processing chain (spec ../shared/spec/volume-slicing-importance.md §2.7) on a
// float RGB image (vsi.post.render_target: float32):
//   1. colour adjustment (vsi.post.adjust): c' = clamp((c - 1/2) κ_c + 1/2 + b, 0, 1)^(1/γ) per channel;
//      identity defaults (κ_c = 1, b = 0, γ = 1) leave values in [0, 1] unchanged (bit for bit);
//   2. 2x2 downsample: each half-resolution pixel the mean of its 2x2 block (an odd last row or
//      column averages the pixels it has), then the threshold (vsi.post.threshold): a pixel whose
//      Rec. 709 luminance 0.2126 R + 0.7152 G + 0.0722 B is below 0.7 becomes 0;
//   3. separable Gaussian (vsi.post.sigma: σ = 2 half-resolution pixels, radius ⌈3σ⌉, weights
//      normalised to sum 1), horizontal then vertical (OpenCV's sepFilter2D, border replicated);
//   4. additive composite (vsi.post.bloom_blend): out = adjusted + gain · bilinear upsample of the
//      blurred image (half-resolution pixel i centred at full-resolution 2i + 1/2; core's
//      sample_bilinear, clamped).

#include <meltlab/core/image.h>

#include <algorithm>
#include <vector>

namespace meltlab::render {

struct ColorAdjust {
  double contrast = 1, brightness = 0, gamma = 1;
  /// The defaults: step 1 only clamps to [0, 1] (identity_value).
  bool identity() const { return contrast == 1 && brightness == 0 && gamma == 1; }
  /// Step 1 of one colour value under the identity adjustment.
  static float identity_value(float v) { return std::clamp(v, 0.0f, 1.0f); }
};

struct BloomSettings {
  bool enabled = false;
  ColorAdjust adjust;
  double threshold = 0.7;  ///< luminance
  double sigma = 2;        ///< half-resolution pixels
  double gain = 1;
};

/// Step 1 (3-channel or more: channels 0-2 adjusted, others copied).
ImageF adjust_colours(const ImageF& image, const ColorAdjust& adjust);
/// Step 1 into `out` (another image than `image`), reusing its storage when it has the size
/// already (a frame loop then touches no new memory); rows in parallel, the same values.
void adjust_colours(const ImageF& image, const ColorAdjust& adjust, ImageF& out);
/// Step 2 without the threshold: the 2x2 block means (width and height rounded up).
ImageF downsample_2x2(const ImageF& image);
/// Step 2's threshold in place: pixels with luminance < threshold set to 0.
void threshold_luminance(ImageF& image, double threshold);
/// The normalised Gaussian kernel of σ (2 ⌈3σ⌉ + 1 weights, summing to 1).
std::vector<double> gaussian_weights(double sigma);
/// Step 3: separable blur with gaussian_weights(sigma).
ImageF gaussian_blur(const ImageF& image, double sigma);
/// Step 4: base + gain · bilinear upsample of `half` to base's size.
ImageF add_upsampled(const ImageF& base, const ImageF& half, double gain);

/// Throws InputError for σ outside (0, 64], γ <= 0, a gain < 0 or a non-finite parameter (what
/// apply_bloom refuses).
void check_bloom_settings(const BloomSettings& settings);
/// Whether the chain only clamps channels 0-2 to [0, 1] (bloom disabled, the identity
/// adjustment): a renderer may then write its pixels clamped and skip the chain (the same bits).
bool bloom_is_clamp(const BloomSettings& settings);

/// The whole chain (steps 1-4; with bloom disabled, step 1 only); check_bloom_settings first.
ImageF apply_bloom(const ImageF& image, const BloomSettings& settings);
/// The chain into `out` (another image than `image`; its storage reused as by adjust_colours).
void apply_bloom(const ImageF& image, const BloomSettings& settings, ImageF& out);

}  // namespace meltlab::render
