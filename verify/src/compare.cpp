#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/compare.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace meltlab::verify {

namespace fs = std::filesystem;

std::int64_t FrameMapping::cycle_of(const Frame& f, const std::string& manifest) const {
  if (seconds_per_cycle) {
    if (!f.time_s)
      throw InputError(fmt::format("{}: frame {} ({}) has no time; --seconds-per-cycle needs time_s or interval_s",
                                   manifest, f.index, f.image.filename().string()));
    return static_cast<std::int64_t>(std::llround(first_cycle + *f.time_s / *seconds_per_cycle));
  }
  const double k = cycles_per_photo.value_or(kDefaultCyclesPerPhoto);
  return static_cast<std::int64_t>(std::llround(first_cycle + k * f.index));
}

cv::Mat overlay_image(const cv::Mat& photo_mask, const cv::Mat& render_mask) {
  CV_Assert(photo_mask.size() == render_mask.size() && photo_mask.type() == CV_8UC1 && render_mask.type() == CV_8UC1);
  cv::Mat out(photo_mask.size(), CV_8UC1, cv::Scalar(255));
  for (int y = 0; y < out.rows; ++y) {
    const auto* a = photo_mask.ptr<std::uint8_t>(y);
    const auto* b = render_mask.ptr<std::uint8_t>(y);
    auto* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < out.cols; ++x) {
      const bool pa = a[x] != 0, pb = b[x] != 0;
      o[x] = pa && pb ? 192 : (pa ? 80 : (pb ? 0 : 255));  // Fig. 8.12 greys
    }
  }
  return out;
}

cv::Mat p_curve_image(const std::vector<FrameResult>& frames, const std::string& title) {
  constexpr int kW = 900, kH = 520, kLeft = 80, kRight = 30, kTop = 50, kBottom = 70;
  cv::Mat img(kH, kW, CV_8UC3, cv::Scalar(255, 255, 255));
  double p_max = 0.25;
  int n_max = 1;
  for (const auto& f : frames) {
    n_max = std::max(n_max, f.frame + 1);
    if (f.status == "ok") p_max = std::max(p_max, f.pixels.P);
  }
  p_max = std::ceil(p_max * 20.0) / 20.0;
  const int pw = kW - kLeft - kRight, ph = kH - kTop - kBottom;
  auto px = [&](double n) { return kLeft + static_cast<int>(std::lround((n - 1) / std::max(1, n_max - 1) * pw)); };
  auto py = [&](double p) { return kTop + ph - static_cast<int>(std::lround(p / p_max * ph)); };
  const cv::Scalar axis(0, 0, 0), grid(225, 225, 225), curve(180, 90, 20), exact(40, 140, 40), accept(40, 40, 200);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (double p = 0; p <= p_max + 1e-9; p += 0.05) {
    cv::line(img, {kLeft, py(p)}, {kLeft + pw, py(p)}, grid, 1);
    cv::putText(img, fmt::format("{:.2f}", p), {10, py(p) + 5}, font, 0.45, axis, 1, cv::LINE_AA);
  }
  const int step = std::max(1, n_max / 10);
  for (int n = 1; n <= n_max; n += step) {
    cv::line(img, {px(n), kTop + ph}, {px(n), kTop + ph + 5}, axis, 1);
    cv::putText(img, std::to_string(n), {px(n) - 8, kTop + ph + 22}, font, 0.45, axis, 1, cv::LINE_AA);
  }
  cv::rectangle(img, {kLeft, kTop}, {kLeft + pw, kTop + ph}, axis, 1);
  for (int x = kLeft; x < kLeft + pw; x += 16)
    cv::line(img, {x, py(0.2)}, {std::min(x + 8, kLeft + pw), py(0.2)}, accept, 1);
  cv::putText(img, "P = 0.2 (acceptance)", {kLeft + pw - 190, py(0.2) - 6}, font, 0.45, accept, 1, cv::LINE_AA);
  auto draw = [&](bool use_exact, const cv::Scalar& colour) {
    std::vector<cv::Point> run;
    auto flush = [&]() {
      if (run.size() > 1) cv::polylines(img, run, false, colour, 2, cv::LINE_AA);
      for (const auto& p : run) cv::circle(img, p, 2, colour, cv::FILLED, cv::LINE_AA);
      run.clear();
    };
    for (const auto& f : frames) {
      if (f.status != "ok" || (use_exact && !f.P_exact)) {
        flush();  // a skipped frame breaks the line
        continue;
      }
      run.push_back({px(f.frame + 1), py(use_exact ? *f.P_exact : f.pixels.P)});
    }
    flush();
  };
  draw(true, exact);
  draw(false, curve);
  cv::putText(img, title, {kLeft, 30}, font, 0.6, axis, 1, cv::LINE_AA);
  cv::putText(img, "photo number", {kLeft + pw / 2 - 50, kH - 20}, font, 0.5, axis, 1, cv::LINE_AA);
  cv::putText(img, "P (pixels)", {kLeft + 10, kTop + 18}, font, 0.5, curve, 1, cv::LINE_AA);
  cv::putText(img, "P (exact polygons)", {kLeft + 120, kTop + 18}, font, 0.5, exact, 1, cv::LINE_AA);
  return img;
}

void write_per_frame_csv(const fs::path& file, const std::vector<FrameResult>& frames) {
  std::ostringstream out;
  out << "frame,image,status,time_s,cycle,S_A,S_B,S_I,P,P_exact,IoU,Dice,Hausdorff_px,Hausdorff_mm,mean_distance_px,"
         "mean_distance_mm,reg_scale,reg_angle_deg,reg_tx_px,reg_ty_px,note\n";
  for (const auto& f : frames) {
    const bool ok = f.status == "ok";
    auto num = [&](double v) { return ok ? fmt::format("{:.8g}", v) : std::string(); };
    auto mm = [&](double v) { return ok && f.mm_per_px > 0 ? fmt::format("{:.8g}", v * f.mm_per_px) : std::string(); };
    out << fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\"\n", f.frame + 1, f.image,
                       f.status, f.time_s ? fmt::format("{:.6g}", *f.time_s) : "", f.cycle, num(f.pixels.S_A),
                       num(f.pixels.S_B), num(f.pixels.S_I), num(f.pixels.P),
                       ok && f.P_exact ? fmt::format("{:.8g}", *f.P_exact) : "", num(f.pixels.IoU), num(f.pixels.Dice),
                       num(f.distances_px.hausdorff), mm(f.distances_px.hausdorff), num(f.distances_px.mean),
                       mm(f.distances_px.mean), num(f.registration.scale),
                       num(f.registration.angle_rad * 180.0 / 3.14159265358979323846),
                       num(f.registration.translation.x()), num(f.registration.translation.y()), f.note);
  }
  write_text_atomically(file, out.str());
}

CompareResult compare_sequence(const ObservationSequence& obs, sim::MeshSequence& meshes, const CompareOptions& options,
                               const std::function<void(const FrameResult&, const FrameImages&)>& on_frame) {
  CompareResult result;
  const std::string manifest = obs.manifest.string();
  render::SilhouetteRenderer binary(obs.camera, render::SilhouetteOptions{1, true});
  render::SilhouetteRenderer soft(obs.camera, render::SilhouetteOptions{std::max(1, options.supersample), true});
  const double units_per_px = render::ground_units_per_pixel(obs.camera);
  const double mm_per_px = units_per_px * 1000.0;  // mesh units are metres
  std::optional<Similarity2D> fixed;
  if (options.registration == RegistrationMode::kGiven) fixed = options.given_registration;
  if (options.registration == RegistrationMode::kNone) fixed = Similarity2D::identity();

  // Frames in cycle order (the mesh sequence only moves forward).
  std::vector<std::size_t> order(obs.frames.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::vector<std::int64_t> cycle(obs.frames.size());
  for (std::size_t i = 0; i < obs.frames.size(); ++i) cycle[i] = options.mapping.cycle_of(obs.frames[i], manifest);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return cycle[a] < cycle[b]; });

  result.frames.resize(obs.frames.size());
  cv::Mat render_mask, render_cov;
  for (std::size_t i : order) {
    const Frame& f = obs.frames[i];
    FrameResult& r = result.frames[i];
    r.frame = f.index;
    r.image = f.image.filename().string();
    r.time_s = f.time_s;
    r.cycle = cycle[i];
    r.mm_per_px = mm_per_px;
    FrameImages images;
    auto skip = [&](const std::string& status, const std::string& note) {
      r.status = status;
      r.note = note;
      ++result.skipped;
      if (on_frame) on_frame(r, images);
    };
    if (options.last_cycle >= 0 && r.cycle > options.last_cycle) {
      skip("beyond_run", fmt::format("cycle {} is beyond the run's last cycle {}", r.cycle, options.last_cycle));
      continue;
    }
    std::error_code ec;
    if (!fs::exists(f.image, ec)) {
      skip("missing", "no such file");
      continue;
    }
    cv::Mat photo;
    try {
      photo = read_image(f.image);
    } catch (const InputError& e) {
      skip("unreadable", e.what());
      continue;
    }
    const Segmentation seg = segment_image(photo, obs.segmentation, obs.roi);
    if (seg.area_px <= 0) {
      skip("empty_photo", "segmentation found no object");
      continue;
    }
    const sim::TriMesh<double>& mesh = meshes.mesh_at(r.cycle);
    binary.render(mesh, render_mask);
    if (render_mask.size() != seg.mask.size())
      throw InputError(fmt::format("{}: frame {} is {}x{} but the camera renders {}x{}", manifest, r.image,
                                   seg.mask.cols, seg.mask.rows, render_mask.cols, render_mask.rows));
    Similarity2D t = fixed.value_or(Similarity2D::identity());
    if (!fixed && cv::countNonZero(render_mask) > 0) {
      const RegistrationResult reg = register_masks(seg.mask, render_mask, options.registration_options);
      t = reg.render_to_photo;
      if (options.registration == RegistrationMode::kFirstFrame) {
        fixed = t;
        result.registration = t;
        result.registration_P_before = reg.P_before;
        result.registration_P_after = reg.P_after;
      }
    }
    r.registration = t;
    images.photo_mask = seg.mask;
    images.render_mask = warp_mask(render_mask, t, seg.mask.size());
    r.pixels = compare_masks(images.photo_mask, images.render_mask);
    r.photo_area_px = seg.area_px;
    r.render_area_px = static_cast<double>(cv::countNonZero(images.render_mask));
    // Sub-pixel contours: the photo's from its segmentation, the render's from a
    // supersampled coverage image at level 0.5, moved by the same registration.
    Region render_region;
    if (r.render_area_px > 0) {
      soft.render(mesh, render_cov);
      render_region = transform_region(
          options.supersample > 1 ? region_from_image(render_cov, 0.5) : region_from_mask(render_cov), t);
    }
    if (options.exact) r.P_exact = compare_regions_exact(seg.region, render_region).P;
    r.distances_px = contour_distances(seg.region, render_region);
    ++result.compared;
    if (on_frame) on_frame(r, images);
  }
  if (options.registration == RegistrationMode::kGiven) result.registration = options.given_registration;
  return result;
}

}  // namespace meltlab::verify
