#pragma once
// Observations of a real (or manufactured) melt: a photo sequence described by a manifest,
// or a mass/volume time series from a CSV file (a kitchen scale), or both.
//
// Manifest (YAML, or JSON with the same keys; paths relative to the manifest's folder;
// unknown keys are errors naming file and line):
//   meltlab_observations: 1
//   object: giraffe                       # free text
//   frames:                               # either an explicit list ...
//     - {image: frames/0001.png, time_s: 0}
//     - {image: frames/0002.png}          # time from interval_s if absent
//   frames: {glob: "frames/*.png"}        # ... or every matching file, sorted by name
//   interval_s: 40                        # time between consecutive frames (default: none)
//   first_time_s: 0
//   camera: {type: orthographic, ...}     # see render/camera.h
//   roi: [x, y, width, height]            # pixels; default: the whole image
//   segmentation: {...}                   # see SegmentationSettings
//   ground_truth: ../truth/giraffe.json   # optional, kept apart from the images
//   mass_series: mass.csv                 # optional time series (see read_time_series)
//   volume_series: volume.csv             # the same key for a volume column (one of the two)
//
// A weighing experiment without photos: a manifest with a mass_series (or volume_series) and
// no frames; camera, roi and segmentation are then not needed (and refused, as typos would
// be). Such a manifest is what `meltlab fit` fits kg (or the time scale) to and what
// `meltlab predict` compares the physics with.

#include <meltlab/core/image.h>
#include <meltlab/render/camera.h>
#include <meltlab/verify/region.h>

#include <opencv2/core.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::verify {

/// How a photo becomes a mask. Defaults work on bright ice on a dark absorbent ground.
struct SegmentationSettings {
  enum class Method { kOtsu, kGlobal, kAdaptive, kBackground };
  Method method = Method::kOtsu;
  /// Channel to threshold: gray | value (HSV V) | lightness (Lab L) | max (max of R,G,B) |
  /// red | green | blue.
  std::string channel = "value";
  double threshold = 128;             ///< kGlobal: 0..255 (8-bit scale; float images are scaled)
  int adaptive_block_px = 101;        ///< kAdaptive: odd neighbourhood size
  double adaptive_offset = -5;        ///< kAdaptive: C of cv::adaptiveThreshold
  std::filesystem::path background;   ///< kBackground: image of the empty scene
  double background_difference = 30;  ///< kBackground: |image - background| > this is object
  bool object_darker = false;         ///< invert: the object is darker than the ground
  double blur_sigma_px = 1.0;         ///< Gaussian pre-blur (0 = none)
  int open_radius_px = 2;             ///< morphological opening (removes specks), 0 = none
  int close_radius_px = 2;            ///< morphological closing (fills cracks), 0 = none
  bool largest_component = true;      ///< keep only the largest connected component
  double min_component_px = 50;       ///< with largest_component = false: drop smaller ones
  bool fill_holes = false;            ///< false keeps holes (the monograph's contours may have them)
  /// The object must stand out: if the mean channel value (|difference| for kBackground) of
  /// the segmented pixels exceeds that of the rest of the ROI by less than this (8-bit
  /// levels), the photo shows no object and the mask is empty. Otsu always splits an image
  /// in two, even bare textured ground after the ice has gone; this refuses such splits.
  /// Bright ice on the dark ground differs by 100+ levels, ground texture by ~10-20. 0 = off.
  double min_contrast = 40;
};

struct Frame {
  int index = 0;                 ///< 0-based position in the sequence
  std::filesystem::path image;   ///< absolute path
  std::optional<double> time_s;  ///< seconds since the first frame's reference
};

struct ObservationSequence {
  std::filesystem::path manifest;
  std::string object;
  std::vector<Frame> frames;
  std::optional<double> interval_s;
  render::Camera camera;
  std::optional<cv::Rect> roi;
  SegmentationSettings segmentation;
  std::optional<std::filesystem::path> ground_truth;
  std::optional<std::filesystem::path> mass_series;  ///< from `mass_series` or `volume_series`

  /// False for a weighing experiment (a series and no frames).
  bool has_photos() const { return !frames.empty(); }
};

/// Reads and validates a manifest (.yaml/.yml/.json). Missing image files are NOT errors
/// here (a frame can be missing; compare reports and skips it) but a frame list that names
/// no existing file at all is. Without `frames` the manifest must name a series (then
/// `frames` is empty and `camera` default). Throws InputError "<manifest>:<line>: <problem>".
ObservationSequence load_observations(const std::filesystem::path& manifest);

/// The edge between meltlab::ImageF (RGB) and OpenCV (BGR): the first 3 channels as BGR (1 or 2
/// channels: the first as grey, alpha dropped) of depth CV_8U/CV_16U (values 0..1 scaled to
/// the integers, rounded) or CV_32F (kHalf, kFloat: the values).
cv::Mat mat_from_image(const ImageF& image, PixelFormat format);
/// The inverse: a CV_8U/CV_16U/CV_32F cv::Mat (BGR or BGRA or grey) as RGB(A) or grey floats,
/// integers divided by their maximum; `format` receives the depth's PixelFormat. Throws
/// InputError for an empty cv::Mat or another depth.
ImageF image_from_mat(const cv::Mat& mat, PixelFormat* format = nullptr);

/// Reads an image with meltlab::read_image as cv::Mat: 8-bit images as CV_8UC1/CV_8UC3 (BGR
/// order, as OpenCV), 16-bit as CV_16U*, float as CV_32F*. Alpha is dropped. Throws InputError
/// "<file>: <problem>" for missing, unreadable, truncated or zero-size images.
cv::Mat read_image(const std::filesystem::path& file);

/// Writes a CV_8U/CV_16U/CV_32F image with meltlab::write_image in the depth's format (format
/// from the extension), atomically.
void write_image(const std::filesystem::path& file, const cv::Mat& image);

struct Segmentation {
  cv::Mat mask;               ///< CV_8UC1, 0/255, full image size (outside the ROI = 0)
  cv::Mat probability;        ///< CV_32FC1 in [0, 1]: smoothed foreground indicator for sub-pixel contours
  Region region;              ///< sub-pixel polygons (with holes) in pixel coordinates
  double area_px = 0;         ///< pixel count of mask
  double threshold_used = 0;  ///< the threshold actually applied (e.g. Otsu's), 8-bit scale
  double contrast = 0;        ///< mean inside minus mean outside (see min_contrast), 8-bit scale
};

/// Segments one photo: channel, blur, threshold, morphology, component selection, holes.
/// Throws InputError if the image is empty; an image whose mask comes out empty is not an
/// error here (area_px = 0; the caller decides).
Segmentation segment_image(const cv::Mat& image, const SegmentationSettings& settings,
                           const std::optional<cv::Rect>& roi = std::nullopt);

/// The threshold half-way between the object and the ground next to a segmentation's
/// boundary: the mean of the medians of the segmented channel (after the pre-blur) over the
/// pixels 2-6 px inside and 2-6 px outside `mask` (within the ROI). A blurred step edge
/// crosses that level at the edge itself, whatever the blur, so the contour at this level
/// estimates the segmentation's sub-pixel bias (verify/fit.h). On the scale of
/// SegmentationSettings::threshold. Nullopt for the adaptive and background methods (no one
/// global level) and when either band is empty.
std::optional<double> mid_level_threshold(const cv::Mat& image, const SegmentationSettings& settings,
                                          const cv::Mat& mask, const std::optional<cv::Rect>& roi = std::nullopt);

/// A time series from CSV: a header line naming the columns, then one row per sample. The
/// columns are `time_s` and one of `mass_kg`, `mass_g`, `volume_m3`, `volume_cm3` (the
/// quantity is taken from the header). Rows must have increasing time; NaN/inf, missing
/// cells and non-numbers are errors naming file and line. Whether the values make a melt
/// (positive, falling) is checked by verify/mass_series.h.
struct TimeSeries {
  std::string quantity;  ///< "mass_kg", "mass_g", "volume_m3" or "volume_cm3"
  std::vector<double> time_s;
  std::vector<double> value;
  std::vector<int> line;  ///< 1-based line of each row in the file (for messages)
  std::filesystem::path file;
};
TimeSeries read_time_series(const std::filesystem::path& csv);

}  // namespace meltlab::verify
