// Seed 003's post-processing chain (see slicing/bloom.h).

#include <meltlab/render/slicing/bloom.h>

#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace meltlab::render {

void adjust_colours(const ImageF& image, const ColorAdjust& a, ImageF& out) {
  if (&out == &image) throw InvariantError("adjust_colours: the output must be another image");
  out.reshape(image.width(), image.height(), image.channels());  // every value is written below
  const bool identity = a.identity();
  const int nc = image.channels(), adjusted = std::min(3, nc);
  auto adjust = [&](float v) {
    if (identity) return ColorAdjust::identity_value(v);
    const double t = std::clamp((double(v) - 0.5) * a.contrast + 0.5 + a.brightness, 0.0, 1.0);
    return float(a.gamma == 1 ? t : std::pow(t, 1.0 / a.gamma));
  };
  tbb::parallel_for(tbb::blocked_range<int>(0, image.height(), 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      const float* in = image.row(y);
      float* o = out.row(y);
      for (int x = 0; x < image.width(); ++x, in += nc, o += nc) {
        for (int c = 0; c < adjusted; ++c) o[c] = adjust(in[c]);
        for (int c = adjusted; c < nc; ++c) o[c] = in[c];
      }
    }
  });
}

ImageF adjust_colours(const ImageF& image, const ColorAdjust& a) {
  ImageF out;
  adjust_colours(image, a, out);
  return out;
}

ImageF downsample_2x2(const ImageF& im) {
  const int w = (im.width() + 1) / 2, h = (im.height() + 1) / 2;
  ImageF out(w, h, im.channels());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < im.channels(); ++c) {
        double s = 0;
        int n = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int xx = 2 * x + dx, yy = 2 * y + dy;
            if (xx < im.width() && yy < im.height()) s += double(im.at(xx, yy, c)), ++n;
          }
        out.at(x, y, c) = float(s / n);
      }
  return out;
}

void threshold_luminance(ImageF& im, double threshold) {
  for (int y = 0; y < im.height(); ++y)
    for (int x = 0; x < im.width(); ++x) {
      const double lum =
          0.2126 * double(im.at(x, y, 0)) + 0.7152 * double(im.at(x, y, 1)) + 0.0722 * double(im.at(x, y, 2));
      if (lum < threshold)
        for (int c = 0; c < im.channels(); ++c) im.at(x, y, c) = 0;
    }
}

std::vector<double> gaussian_weights(double sigma) {
  const int r = int(std::ceil(3 * sigma));
  std::vector<double> w(std::size_t(2 * r + 1));
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += w[std::size_t(i + r)] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& x : w) x /= sum;
  return w;
}

ImageF gaussian_blur(const ImageF& im, double sigma) {
  const auto w = gaussian_weights(sigma);
  cv::Mat kernel(int(w.size()), 1, CV_32F);
  for (std::size_t i = 0; i < w.size(); ++i) kernel.at<float>(int(i)) = float(w[i]);
  ImageF out(im.width(), im.height(), im.channels());
  const cv::Mat src(im.height(), im.width(), CV_32FC(im.channels()), const_cast<float*>(im.data()));
  cv::Mat dst(out.height(), out.width(), CV_32FC(out.channels()), out.data());
  cv::sepFilter2D(src, dst, CV_32F, kernel, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  return out;
}

ImageF add_upsampled(const ImageF& base, const ImageF& half, double gain) {
  ImageF out = base;
  for (int y = 0; y < out.height(); ++y)
    for (int x = 0; x < out.width(); ++x) {
      const double u = 0.5 * x - 0.25, v = 0.5 * y - 0.25;  // full-resolution centre x in half-resolution pixels
      for (int c = 0; c < std::min(base.channels(), half.channels()); ++c)
        out.at(x, y, c) += float(gain * sample_bilinear(half, u, v, c, ImageWrap::kClamp, ImageWrap::kClamp));
    }
  return out;
}

void check_bloom_settings(const BloomSettings& s) {
  if (!(s.adjust.gamma > 0 && std::isfinite(s.adjust.gamma) && std::isfinite(s.adjust.contrast) &&
        std::isfinite(s.adjust.brightness)))
    throw InputError("slicing: bloom: gamma must be > 0 and contrast, brightness finite");
  if (!(s.sigma > 0 && s.sigma <= 64))
    throw InputError(fmt::format("slicing: bloom: sigma must be in (0, 64] (got {})", s.sigma));
  if (!(s.gain >= 0 && std::isfinite(s.gain) && std::isfinite(s.threshold)))
    throw InputError("slicing: bloom: gain must be >= 0 and the threshold finite");
}

bool bloom_is_clamp(const BloomSettings& s) { return !s.enabled && s.adjust.identity(); }

void apply_bloom(const ImageF& image, const BloomSettings& s, ImageF& out) {
  check_bloom_settings(s);
  if (image.channels() < 3) throw InvariantError("apply_bloom: an RGB image is needed");
  adjust_colours(image, s.adjust, out);
  if (!s.enabled) return;
  ImageF half = downsample_2x2(out);
  threshold_luminance(half, s.threshold);
  out = add_upsampled(out, gaussian_blur(half, s.sigma), s.gain);
}

ImageF apply_bloom(const ImageF& image, const BloomSettings& s) {
  ImageF out;
  apply_bloom(image, s, out);
  return out;
}

}  // namespace meltlab::render
