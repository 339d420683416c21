// Segmentation of one photo into object / ground (observations.h).
//
// Pipeline: colour -> one channel on the 8-bit scale (float) -> optional Gaussian blur ->
// a signed score S (object where S > 0) -> ROI -> morphology -> component selection ->
// holes. The same score gives the sub-pixel contour: the probability image follows S
// linearly near the boundary (its 0.5 level is S = 0 where mask and S agree), but is
// clamped to the mask's side of 0.5 at every pixel centre, so region_from_image(p, 0.5)
// has exactly the mask's inside/outside pixel centres, with sub-pixel boundary positions.
//
// Scores:
//   Otsu / global : S = C - t              (t from cv::threshold THRESH_OTSU, or `threshold`)
//   adaptive      : S = C - (mean_b(C) - offset)   (cv::adaptiveThreshold's MEAN_C, computed
//                                                    in floating point, replicated border)
//   background    : S = |C - C_background| - background_difference
// with C = 255 - channel when object_darker (for Otsu/global/adaptive; the background
// difference is absolute, so object_darker does not change it).

#include "obs_detail.h"

#include <meltlab/core/error.h>
#include <meltlab/verify/observations.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace meltlab::verify {

namespace detail {

bool known_channel(const std::string& channel) {
  static const std::array<const char*, 7> kChannels = {"gray", "value", "lightness", "max", "red", "green", "blue"};
  return std::any_of(kChannels.begin(), kChannels.end(), [&](const char* c) { return channel == c; });
}

std::string segmentation_settings_problem(const SegmentationSettings& s) {
  constexpr int kMaxRadius = 1000;
  if (!known_channel(s.channel)) {
    return fmt::format("channel: unknown channel '{}' (gray, value, lightness, max, red, green or blue)", s.channel);
  }
  if (!std::isfinite(s.threshold) || s.threshold < 0 || s.threshold > 255) {
    return fmt::format("threshold: must be a number in [0, 255] (got {})", s.threshold);
  }
  if (s.adaptive_block_px < 3 || s.adaptive_block_px % 2 == 0) {
    return fmt::format("adaptive_block_px: must be an odd number >= 3 (got {})", s.adaptive_block_px);
  }
  if (!std::isfinite(s.adaptive_offset) || std::abs(s.adaptive_offset) > 255) {
    return fmt::format("adaptive_offset: must be a number in [-255, 255] (got {})", s.adaptive_offset);
  }
  if (s.method == SegmentationSettings::Method::kBackground && s.background.empty()) {
    return "background: the background method needs a background image";
  }
  if (!std::isfinite(s.background_difference) || s.background_difference < 0 || s.background_difference > 255) {
    return fmt::format("background_difference: must be a number in [0, 255] (got {})", s.background_difference);
  }
  if (!std::isfinite(s.blur_sigma_px) || s.blur_sigma_px < 0 || s.blur_sigma_px > 100) {
    return fmt::format("blur_sigma_px: must be a number in [0, 100] (got {})", s.blur_sigma_px);
  }
  if (s.open_radius_px < 0 || s.open_radius_px > kMaxRadius) {
    return fmt::format("open_radius_px: must be in [0, {}] (got {})", kMaxRadius, s.open_radius_px);
  }
  if (s.close_radius_px < 0 || s.close_radius_px > kMaxRadius) {
    return fmt::format("close_radius_px: must be in [0, {}] (got {})", kMaxRadius, s.close_radius_px);
  }
  if (!std::isfinite(s.min_contrast) || s.min_contrast < 0 || s.min_contrast > 255) {
    return fmt::format("min_contrast: must be a number in [0, 255] (got {})", s.min_contrast);
  }
  if (!std::isfinite(s.min_component_px) || s.min_component_px < 0) {
    return fmt::format("min_component_px: must be a number >= 0 (got {})", s.min_component_px);
  }
  return {};
}

}  // namespace detail

namespace {

/// The image as float BGR (or grey) in [0, 1]: 8-bit / 255, 16-bit / 65535, float as is.
cv::Mat to_unit_float(const cv::Mat& image) {
  cv::Mat src = image;
  if (src.channels() == 4) {
    cv::cvtColor(src, src, cv::COLOR_BGRA2BGR);
  } else if (src.channels() == 2) {
    cv::extractChannel(src, src, 0);
  } else if (src.channels() != 1 && src.channels() != 3) {
    throw InputError(fmt::format("segmentation: cannot segment a {}-channel image", src.channels()));
  }
  double scale = 1.0;
  switch (src.depth()) {
    case CV_8U:
      scale = 1.0 / 255.0;
      break;
    case CV_16U:
      scale = 1.0 / 65535.0;
      break;
    case CV_32F:
    case CV_64F:
      scale = 1.0;
      break;
    default:
      throw InputError(fmt::format("segmentation: unsupported pixel depth {}", src.depth()));
  }
  cv::Mat out;
  src.convertTo(out, CV_MAKETYPE(CV_32F, src.channels()), scale);
  // Non-finite pixels (possible in EXR) count as black.
  cv::patchNaNs(out, 0.0);
  return out;
}

/// One channel on the 8-bit scale (CV_32FC1, nominally 0..255).
cv::Mat select_channel(const cv::Mat& unit, const std::string& channel) {
  cv::Mat c;
  if (unit.channels() == 1) {
    c = unit.clone();
  } else if (channel == "gray") {
    cv::cvtColor(unit, c, cv::COLOR_BGR2GRAY);
  } else if (channel == "value" || channel == "max") {
    // HSV's V is max(R, G, B).
    std::array<cv::Mat, 3> bgr;
    cv::split(unit, bgr.data());
    c = cv::max(cv::max(bgr[0], bgr[1]), bgr[2]);
  } else if (channel == "lightness") {
    cv::Mat unit_clamped = cv::min(cv::max(unit, 0.0), 1.0);
    cv::Mat lab;
    cv::cvtColor(unit_clamped, lab, cv::COLOR_BGR2Lab);  // float: L in [0, 100]
    cv::extractChannel(lab, c, 0);
    c *= 1.0 / 100.0;
  } else {
    const int index = channel == "blue" ? 0 : (channel == "green" ? 1 : 2);
    cv::extractChannel(unit, c, index);
  }
  c *= 255.0;
  return c;
}

cv::Mat channel_of(const cv::Mat& image, const SegmentationSettings& s) {
  cv::Mat c = select_channel(to_unit_float(image), s.channel);
  if (s.blur_sigma_px > 0)
    cv::GaussianBlur(c, c, cv::Size(0, 0), s.blur_sigma_px, s.blur_sigma_px, cv::BORDER_REPLICATE);
  return c;
}

cv::Mat ellipse_kernel(int radius) {
  return cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
}

/// Keeps the largest 8-connected component, or all of at least `min_px` pixels.
cv::Mat select_components(const cv::Mat& mask, bool largest, double min_px) {
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<unsigned char> keep(static_cast<std::size_t>(n), 0);
  if (largest) {
    int best = 0, best_area = 0;
    for (int i = 1; i < n; ++i) {
      const int area = stats.at<int>(i, cv::CC_STAT_AREA);
      if (area > best_area) best = i, best_area = area;
    }
    if (best > 0) keep[static_cast<std::size_t>(best)] = 255;
  } else {
    for (int i = 1; i < n; ++i) {
      if (stats.at<int>(i, cv::CC_STAT_AREA) >= min_px) keep[static_cast<std::size_t>(i)] = 255;
    }
  }
  cv::Mat out(mask.size(), CV_8UC1);
  for (int y = 0; y < mask.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    unsigned char* o = out.ptr<unsigned char>(y);
    for (int x = 0; x < mask.cols; ++x) o[x] = keep[static_cast<std::size_t>(l[x])];
  }
  return out;
}

/// Fills the holes of a mask: 4-connected background components not touching the border.
void fill_holes(cv::Mat& mask) {
  cv::Mat background = mask == 0;
  cv::Mat labels;
  const int n = cv::connectedComponents(background, labels, 4, CV_32S);
  std::vector<unsigned char> outside(static_cast<std::size_t>(n), 0);
  const auto mark = [&](int y, int x) { outside[static_cast<std::size_t>(labels.at<int>(y, x))] = 1; };
  for (int x = 0; x < mask.cols; ++x) mark(0, x), mark(mask.rows - 1, x);
  for (int y = 0; y < mask.rows; ++y) mark(y, 0), mark(y, mask.cols - 1);
  for (int y = 0; y < mask.rows; ++y) {
    const int* l = labels.ptr<int>(y);
    unsigned char* m = mask.ptr<unsigned char>(y);
    for (int x = 0; x < mask.cols; ++x) {
      if (l[x] > 0 && !outside[static_cast<std::size_t>(l[x])]) m[x] = 255;
    }
  }
}

// The part of the image segmented: the whole image or the checked ROI.
cv::Rect segmented_area(const cv::Mat& image, const std::optional<cv::Rect>& roi) {
  const cv::Rect whole(0, 0, image.cols, image.rows);
  if (!roi) return whole;
  if (roi->width <= 0 || roi->height <= 0 || (*roi & whole) != *roi) {
    throw InputError(fmt::format("segmentation: roi [{}, {}, {}, {}] is not inside the {}x{} image", roi->x, roi->y,
                                 roi->width, roi->height, image.cols, image.rows));
  }
  return *roi;
}

// The signed score of the method (object where score > 0) and the image whose inside and
// outside means must differ; sets out.threshold_used.
struct Score {
  cv::Mat score, contrast_of;
};
Score signed_score(const cv::Mat& image, const SegmentationSettings& settings, const cv::Rect& area,
                   Segmentation& out) {
  using Method = SegmentationSettings::Method;
  cv::Mat c = channel_of(image, settings);
  const bool invert = settings.object_darker && settings.method != Method::kBackground;
  if (invert) c = 255.0 - c;
  Score s;
  s.contrast_of = c;
  switch (settings.method) {
    case Method::kOtsu: {
      cv::Mat c8;
      c(area).convertTo(c8, CV_8U);  // rounds and saturates
      const double t = cv::threshold(c8, c8, 0, 255, cv::THRESH_BINARY | cv::THRESH_OTSU);
      s.score = c - t;
      out.threshold_used = invert ? 255.0 - t : t;
      break;
    }
    case Method::kGlobal: {
      const double t = invert ? 255.0 - settings.threshold : settings.threshold;
      s.score = c - t;
      out.threshold_used = settings.threshold;
      break;
    }
    case Method::kAdaptive: {
      cv::Mat local;
      const int b = settings.adaptive_block_px;
      cv::boxFilter(c, local, CV_32F, cv::Size(b, b), cv::Point(-1, -1), true, cv::BORDER_REPLICATE);
      local -= settings.adaptive_offset;
      s.score = c - local;
      const double mean_t = cv::mean(local(area))[0];
      out.threshold_used = invert ? 255.0 - mean_t : mean_t;
      break;
    }
    case Method::kBackground: {
      const cv::Mat bg_image = read_image(settings.background);
      if (bg_image.size() != image.size()) {
        throw InputError(fmt::format("{}: background is {}x{} but the image is {}x{}", settings.background.string(),
                                     bg_image.cols, bg_image.rows, image.cols, image.rows));
      }
      const cv::Mat bg = channel_of(bg_image, settings);
      cv::Mat diff;
      cv::absdiff(c, bg, diff);
      s.score = diff - settings.background_difference;
      s.contrast_of = diff;
      out.threshold_used = settings.background_difference;
      break;
    }
  }
  return s;
}

// The object mask: the score thresholded inside the ROI, opened and closed (outside the image
// counts as neutral; the ROI border as ground), its components selected, its holes filled.
cv::Mat object_mask(const cv::Mat& score, const cv::Rect& area, const SegmentationSettings& settings) {
  const cv::Rect whole(0, 0, score.cols, score.rows);
  cv::Mat mask = cv::Mat::zeros(score.size(), CV_8UC1);
  {
    cv::Mat inside = score(area) > 0;
    inside.copyTo(mask(area));
  }
  if (settings.open_radius_px > 0)
    cv::morphologyEx(mask, mask, cv::MORPH_OPEN, ellipse_kernel(settings.open_radius_px));
  if (settings.close_radius_px > 0) {
    cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, ellipse_kernel(settings.close_radius_px));
    if (area != whole) {
      cv::Mat clipped = cv::Mat::zeros(score.size(), CV_8UC1);
      mask(area).copyTo(clipped(area));
      mask = clipped;
    }
  }
  mask = select_components(mask, settings.largest_component, settings.min_component_px);
  if (settings.fill_holes) fill_holes(mask);
  return mask;
}

// Is there an object at all? The difference of the means of `contrast_of` inside and outside
// the mask within the ROI (0 if either side is empty).
double object_contrast(const cv::Mat& mask, const cv::Mat& contrast_of, const cv::Rect& area) {
  const cv::Mat m = mask(area), v = contrast_of(area);
  const double n_in = cv::countNonZero(m), n_all = static_cast<double>(area.area());
  if (!(n_in > 0 && n_in < n_all)) return 0;
  cv::Mat outside;
  cv::bitwise_not(m, outside);
  return cv::mean(v, m)[0] - cv::mean(v, outside)[0];
}

// Probability: linear in the score near the boundary, on the mask's side of 0.5 at every
// pixel centre. Where mask and score disagree (morphology, removed components, filled
// holes) the pixel gets 0.75 / 0.25, i.e. a boundary about half-way to its neighbours.
cv::Mat object_probability(const cv::Mat& score, const cv::Mat& mask, const cv::Rect& area) {
  double score_scale = 1.0;
  {
    double lo = 0, hi = 0;
    cv::minMaxLoc(score(area), &lo, &hi);
    score_scale = std::max({1.0, std::abs(lo), std::abs(hi)});
  }
  constexpr float kEps = 1e-4F;
  cv::Mat probability = cv::Mat::zeros(score.size(), CV_32FC1);
  for (int y = area.y; y < area.y + area.height; ++y) {
    const float* s = score.ptr<float>(y);
    const unsigned char* m = mask.ptr<unsigned char>(y);
    float* p = probability.ptr<float>(y);
    for (int x = area.x; x < area.x + area.width; ++x) {
      const float v = static_cast<float>(0.5 + 0.5 * std::clamp(static_cast<double>(s[x]) / score_scale, -1.0, 1.0));
      if (m[x]) {
        p[x] = s[x] > 0 ? std::max(v, 0.5F + kEps) : 0.75F;
      } else {
        p[x] = s[x] > 0 ? 0.25F : std::min(v, 0.5F - kEps);
      }
    }
  }
  return probability;
}

}  // namespace

Segmentation segment_image(const cv::Mat& image, const SegmentationSettings& settings,
                           const std::optional<cv::Rect>& roi) {
  if (image.empty()) throw InputError("segmentation: empty image");
  if (const std::string problem = detail::segmentation_settings_problem(settings); !problem.empty()) {
    throw InputError("segmentation." + problem);
  }
  const cv::Rect area = segmented_area(image, roi);
  Segmentation out;
  const Score s = signed_score(image, settings, area, out);
  cv::Mat mask = object_mask(s.score, area, settings);
  out.contrast = object_contrast(mask, s.contrast_of, area);
  if (cv::countNonZero(mask(area)) > 0 && settings.min_contrast > 0 && out.contrast < settings.min_contrast)
    mask.setTo(0);
  out.area_px = cv::countNonZero(mask);
  out.probability = object_probability(s.score, mask, area);
  out.region = out.area_px > 0 ? region_from_image(out.probability, 0.5) : Region{};
  out.mask = std::move(mask);
  return out;
}

std::optional<double> mid_level_threshold(const cv::Mat& image, const SegmentationSettings& settings,
                                          const cv::Mat& mask, const std::optional<cv::Rect>& roi) {
  using Method = SegmentationSettings::Method;
  if (settings.method == Method::kAdaptive || settings.method == Method::kBackground) return std::nullopt;
  if (image.empty() || mask.size() != image.size() || mask.type() != CV_8UC1)
    throw InvariantError("mid_level_threshold: a CV_8UC1 mask of the image's size");
  const cv::Mat c = channel_of(image, settings);  // the raw channel: the threshold's scale
  const cv::Rect whole(0, 0, image.cols, image.rows);
  const cv::Rect area = roi ? (*roi & whole) : whole;
  // Only pixels near the segmentation's contour count (not other bright things).
  cv::Mat near_in, near_out, ground;
  cv::distanceTransform(mask, near_in, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::bitwise_not(mask, ground);
  cv::distanceTransform(ground, near_out, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  // 2 px: beyond most of the blur of a sharp camera (sigma ~1.4 px with the pre-blur: 92 % of
  // the step); 6 px: still next to the contour of a thin part. The bands are measured from
  // the contour at the current level and the level recomputed until they sit symmetrically
  // about it (a biased first contour puts one band on the edge's slope).
  constexpr float kNear = 2.0F, kFar = 6.0F, kReach = 12.0F;
  constexpr int kIterations = 4;
  cv::Mat current = mask.clone();
  std::optional<double> level;
  auto median = [](std::vector<float>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return static_cast<double>(*mid);
  };
  const bool darker = settings.object_darker;
  for (int it = 0; it < kIterations; ++it) {
    cv::Mat inside_d, outside_d, outside;
    cv::distanceTransform(current, inside_d, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    cv::bitwise_not(current, outside);
    cv::distanceTransform(outside, outside_d, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    std::vector<float> in, out;
    for (int y = area.y; y < area.y + area.height; ++y) {
      const float* v = c.ptr<float>(y);
      const float* di = inside_d.ptr<float>(y);
      const float* d_o = outside_d.ptr<float>(y);
      const float* ni = near_in.ptr<float>(y);
      const float* no = near_out.ptr<float>(y);
      for (int x = area.x; x < area.x + area.width; ++x) {
        if (ni[x] > kReach || no[x] > kReach) continue;
        if (di[x] >= kNear && di[x] <= kFar) in.push_back(v[x]);
        if (d_o[x] >= kNear && d_o[x] <= kFar) out.push_back(v[x]);
      }
    }
    if (in.empty() || out.empty()) return level;
    level = std::clamp(0.5 * (median(in) + median(out)), 0.0, 255.0);
    // The contour at this level, near the segmentation's.
    current = darker ? (c < *level) : (c > *level);
    current.convertTo(current, CV_8U);
  }
  return level;
}

}  // namespace meltlab::verify
