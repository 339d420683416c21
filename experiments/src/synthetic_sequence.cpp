#include <meltlab/core/run_folder.h>
#include <meltlab/core/hash.h>
#include <meltlab/experiments/sequence_manifest.h>
#include <meltlab/experiments/run_replay.h>
#include <meltlab/experiments/synthetic_sequence.h>
#include <meltlab/render/raster/silhouette.h>
#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/sim/quality.h>
#include <meltlab/verify/observations.h>
#include <meltlab/experiments/provenance.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <sstream>

namespace meltlab::experiments {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// Smooth random texture in [-1, 1]: white noise blurred at `scale_px`, normalised.
cv::Mat smooth_noise(cv::Size size, double scale_px, cv::RNG& rng) {
  cv::Mat n(size, CV_32FC1);
  rng.fill(n, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(n, n, cv::Size(), scale_px);
  double lo = 0, hi = 0;
  cv::minMaxLoc(n, &lo, &hi);
  const double half = std::max(std::abs(lo), std::abs(hi));
  if (half > 0) n *= 1.0 / half;
  return n;
}

/// The default camera: straight down, centred on the mesh's footprint, scaled so that the
/// footprint spans `fill` of the image.
render::Camera framing_camera(const sim::IndexedMesh& mesh, int width, int height, double fill) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (const auto& p : mesh.V) {
    lo = lo.cwiseMin(p.head<2>());
    hi = hi.cwiseMax(p.head<2>());
  }
  const Eigen::Vector2d extent = (hi - lo).cwiseMax(1e-12);
  render::OrthographicTopDown cam;
  cam.width = width;
  cam.height = height;
  cam.centre = 0.5 * (lo + hi);
  cam.pixels_per_unit = fill * std::min(width / extent.x(), height / extent.y());
  return cam;
}

/// Writes an 8-bit image as JPEG (quality q) or PNG, atomically.
void write_photo(const fs::path& file, const cv::Mat& bgr, int jpeg_quality) {
  if (jpeg_quality <= 0) {
    verify::write_image(file, bgr);
    return;
  }
  meltlab::write_image(file, verify::image_from_mat(bgr), PixelFormat::kUint8, jpeg_quality);
}

void check_options(const SyntheticSequenceOptions& o) {
  require(o.photos >= 1 && o.photos <= 100000, fmt::format("--photos: must be in [1, 100000] (got {})", o.photos));
  require(std::isfinite(o.cycles_per_photo) && o.cycles_per_photo > 0,
          fmt::format("--cycles-per-photo: must be a finite number > 0 (got {})", o.cycles_per_photo));
  require(std::isfinite(o.interval_s) && o.interval_s > 0,
          fmt::format("--interval-s: must be > 0 (got {})", o.interval_s));
  require(o.width >= 16 && o.height >= 16 && o.width <= 16384 && o.height <= 16384,
          fmt::format("--width/--height: must be in [16, 16384] (got {}x{})", o.width, o.height));
  require(std::isfinite(o.fill) && o.fill > 0 && o.fill <= 1,
          fmt::format("--fill: must be in (0, 1] (got {})", o.fill));
  require(std::isfinite(o.noise_sigma) && o.noise_sigma >= 0, "--noise: must be >= 0");
  require(std::isfinite(o.blur_sigma_px) && o.blur_sigma_px >= 0, "--blur: must be >= 0");
  require(o.jpeg_quality >= 0 && o.jpeg_quality <= 100, "--jpeg-quality: must be in [0, 100]");
  const auto& mis = o.misalignment;
  require(std::isfinite(mis.scale) && mis.scale > 0 && std::isfinite(mis.angle_rad) && mis.translation.allFinite(),
          "--misalign: scale must be > 0 and all values finite");
}

// The fixed scene of the photos: a dark absorbent ground with a fine texture, ice with a milky
// texture, and light falling off across the table (as from a lamp at one side).
struct PhotoScene {
  cv::Mat ground_tex, ice_tex, lighting;

  PhotoScene(cv::Size size, std::uint64_t seed) {
    cv::RNG rng(seed);
    ground_tex = smooth_noise(size, 2.0, rng);
    ice_tex = smooth_noise(size, 12.0, rng);
    lighting = cv::Mat(size, CV_32FC1);
    for (int y = 0; y < size.height; ++y)
      for (int x = 0; x < size.width; ++x)
        lighting.at<float>(y, x) = static_cast<float>(0.85 + 0.25 * x / size.width - 0.1 * y / size.height);
  }

  // Photo k of the ice covering `coverage` (in [0, 1] per pixel, already misaligned): the
  // scene, blurred, with sensor noise, in 8 bits (`out8`; `image` and `noise` are scratch).
  void photograph(const cv::Mat& coverage, const SyntheticSequenceOptions& o, int k, cv::Mat& image, cv::Mat& noise,
                  cv::Mat& out8) const {
    for (int y = 0; y < image.rows; ++y) {
      const float* c = coverage.ptr<float>(y);
      const float* g = ground_tex.ptr<float>(y);
      const float* t = ice_tex.ptr<float>(y);
      const float* l = lighting.ptr<float>(y);
      auto* px = image.ptr<cv::Vec3f>(y);
      for (int x = 0; x < image.cols; ++x) {
        const float ground = 38.0f + 10.0f * g[x];
        const float ice = 200.0f + 25.0f * t[x];
        const float v = l[x] * (ground + c[x] * (ice - ground));
        px[x] = cv::Vec3f(v * 1.04f, v, v * 0.95f);  // BGR: slightly cool ice light
      }
    }
    cv::Mat blurred;
    if (o.blur_sigma_px > 0)
      cv::GaussianBlur(image, blurred, cv::Size(), o.blur_sigma_px);
    else
      blurred = image;
    cv::RNG frame_rng(o.seed * 7919u + static_cast<std::uint64_t>(k) + 1u);
    frame_rng.fill(noise, cv::RNG::NORMAL, 0.0, o.noise_sigma);
    blurred += noise;
    blurred.convertTo(out8, CV_8UC3);  // saturates to [0, 255]
  }
};

// truth/truth.json without its frames and provenance.
json truth_json(const SyntheticSequenceOptions& o, const RunReplay& simulation) {
  const auto& mis = o.misalignment;
  json truth;
  truth["generator"] = "meltlab synth-sequence (empirical model, inverse-crime data)";
  truth["simulation"] = options_to_json(o.simulation);
  truth["mesh_hash"] = file_hash(simulation.prepared().mesh_path);
  truth["resolved"] = {{"kE", simulation.prepared().params.kE},
                       {"kN", simulation.prepared().params.kN},
                       {"kr", simulation.prepared().params.kr},
                       {"mean_edge_length", simulation.prepared().mean_edge_length}};
  truth["cycles_per_photo"] = o.cycles_per_photo;
  truth["interval_s"] = o.interval_s;
  truth["seconds_per_cycle"] = o.interval_s / o.cycles_per_photo;
  truth["misalignment"] = {{"scale", mis.scale},
                           {"angle_deg", mis.angle_rad * 180.0 / 3.14159265358979323846},
                           {"tx_px", mis.translation.x()},
                           {"ty_px", mis.translation.y()}};
  truth["seed"] = o.seed;
  truth["image_model"] = {
      {"noise_sigma", o.noise_sigma}, {"blur_sigma_px", o.blur_sigma_px}, {"jpeg_quality", o.jpeg_quality}};
  return truth;
}

}  // namespace

void make_synthetic_sequence(const SyntheticSequenceOptions& o,
                             const std::function<void(const SyntheticProgress&)>& progress) {
  check_options(o);
  RunFolder folder(o.out_dir, {"--out", "manifest.yaml", "sequence", o.overwrite});
  Provenance provenance = start_provenance("synth-sequence", o.command_line);
  const fs::path& dir = folder.path();

  RunReplay simulation(o.simulation);
  const render::Camera camera =
      o.camera ? *o.camera : framing_camera(simulation.prepared().mesh, o.width, o.height, o.fill);
  const int width = render::camera_width(camera), height = render::camera_height(camera);
  const cv::Size size(width, height);
  create_output_directories(dir / "frames", "--out");
  create_output_directories(dir / "truth" / "masks", "--out");
  const PhotoScene scene(size, o.seed);

  // ---- per photo: the model's mesh at its cycle, its coverage misaligned, the photo ----
  render::SilhouetteRenderer renderer(camera, render::SilhouetteOptions{4, true});
  const cv::Mat warp = o.misalignment.matrix();
  json frames = json::array();
  std::ostringstream volume_csv;
  volume_csv << "time_s,volume_m3\n";
  std::vector<std::string> images;
  cv::Mat coverage, photo_cov, image(size, CV_32FC3), noise(size, CV_32FC3), out8;
  for (int k = 0; k < o.photos; ++k) {
    const auto cycle = static_cast<std::int64_t>(std::llround(k * o.cycles_per_photo));
    const double time_s = k * o.interval_s;
    const sim::TriMesh<double>& mesh = simulation.mesh_at(cycle);
    renderer.render(mesh, coverage);
    cv::warpAffine(coverage, photo_cov, warp, size, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    const cv::Mat truth_mask = photo_cov >= 0.5f;
    scene.photograph(photo_cov, o, k, image, noise, out8);
    const std::string name = fmt::format("frame_{:04d}.{}", k + 1, o.jpeg_quality > 0 ? "jpg" : "png");
    write_photo(dir / "frames" / name, out8, o.jpeg_quality);
    verify::write_image(dir / "truth" / "masks" / fmt::format("frame_{:04d}.png", k + 1), truth_mask);
    const double volume = mesh.live_triangle_count() > 0 ? sim::mesh_volume(mesh) : 0.0;
    frames.push_back({{"frame", k + 1},
                      {"image", "frames/" + name},
                      {"time_s", time_s},
                      {"cycle", cycle},
                      {"true_area_px", cv::countNonZero(truth_mask)},
                      {"true_coverage_px", cv::sum(photo_cov)[0]},
                      {"volume", volume},
                      {"triangles", mesh.live_triangle_count()}});
    volume_csv << fmt::format("{},{:.10g}\n", time_s, volume);
    images.push_back("frames/" + name);
    if (progress) progress({k + 1, o.photos});
  }

  // ---- the truth, then the manifest ----
  write_text_atomically(dir / "volume.csv", volume_csv.str());
  json truth = truth_json(o, simulation);
  truth["frames"] = frames;
  SequenceManifest manifest;
  manifest.comment =
      "Made by meltlab synth-sequence (the empirical model: inverse-crime data). Truth: truth/truth.json";
  manifest.object = fs::path(o.simulation.mesh).stem().string();
  manifest.interval_s = o.interval_s;
  manifest.camera = camera;
  manifest.mass_series = "volume.csv";
  manifest.images = images;
  finish_generated_sequence(folder, std::move(truth), provenance, manifest);
}

}  // namespace meltlab::experiments
