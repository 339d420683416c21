// Reading observation manifests (observations.h).
//
// YAML and JSON manifests go through the same code: JSON is first checked with
// nlohmann::json (JSON syntax errors with their line), then loaded with yaml-cpp (YAML is a
// superset of JSON), which keeps the line of every node for messages. Every message is one
// line, "<manifest>:<line>: <problem>", naming the key concerned.
//
// Choices where observations.h leaves room:
//  - `camera` is required with frames (the comparison renders the simulation with it); its
//    width and height must equal the first readable frame's size. Without frames (a mass or
//    volume series alone) camera, roi and segmentation are refused.
//  - frame times: an explicit time_s wins; otherwise first_time_s + index * interval_s when
//    interval_s is given; otherwise the first frame gets first_time_s if that is given, and
//    other frames have no time. Known times must strictly increase.
//  - a frame entry is {image: path, time_s: t} or just a path string.
//  - glob: wildcards (* ? [..]) only in the last path component; sorted by file name.
//  - ground_truth, mass_series and segmentation.background must exist (their errors are
//    better found here than half-way through a comparison); the background must be a
//    readable image of the frames' size.
//  - duplicate keys in a mapping are errors (as in every config, core/config.h).

#include "obs_detail.h"

#include <meltlab/core/config.h>
#include <meltlab/core/input_file.h>
#include <meltlab/render/camera.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/observations.h>

#include <fmt/format.h>
#include <fnmatch.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace meltlab::verify {

namespace fs = std::filesystem;

namespace {

/// Where the manifest is: relative paths in it are relative to its folder.
struct Ctx {
  std::string file;
  fs::path dir;  ///< absolute folder of the manifest

  fs::path resolve(const std::string& p) const {
    const fs::path path(p);
    return (path.is_absolute() ? path : dir / path).lexically_normal();
  }
};

/// An integer written as any number with an integral value ("51", "51.0", "5.1e1"): manifests
/// come from tools that write JSON numbers as doubles.
int whole_number(const ConfigValue& v) {
  const double x = v.as<double>();
  if (x != std::floor(x) || std::abs(x) > 1e9) v.fail(fmt::format("must be an integer (got '{}')", v.scalar()));
  return static_cast<int>(x);
}

std::string path_text(const ConfigValue& v) {
  std::string s = v.as<std::string>();
  if (s.empty()) v.fail("must be a non-empty path");
  return s;
}

fs::path existing_file(const Ctx& ctx, const ConfigValue& v) {
  const fs::path p = ctx.resolve(path_text(v));
  std::error_code ec;
  if (!fs::is_regular_file(p, ec))
    v.fail(fmt::format("{} {}", p.string(), fs::exists(p, ec) ? "is not a file" : "does not exist"));
  return p;
}

YAML::Node load_yaml(const fs::path& manifest, const std::string& file) {
  std::error_code ec;
  if (fs::is_directory(manifest, ec)) throw InputError(fmt::format("{}: is a directory, not a manifest", file));
  std::string content = read_text_file(manifest, "manifest");
  if (content.find_first_not_of(" \t\r\n") == std::string::npos)
    throw InputError(fmt::format("{}: empty manifest", file));

  std::string ext = manifest.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".json") {
    try {
      [[maybe_unused]] const nlohmann::json parsed = nlohmann::json::parse(content);
    } catch (const nlohmann::json::parse_error& e) {
      // Byte offset -> line.
      const std::size_t upto = std::min(e.byte, content.size());
      const auto line = 1 + std::count(content.begin(), content.begin() + static_cast<std::ptrdiff_t>(upto), '\n');
      std::string what = e.what();
      if (const auto pos = what.find("parse error"); pos != std::string::npos) what = what.substr(pos);
      throw InputError(fmt::format("{}:{}: JSON syntax error: {}", file, line, one_line(what)));
    } catch (const nlohmann::json::exception& e) {  // e.g. a number too large for a double
      throw InputError(fmt::format("{}: JSON error: {}", file, one_line(e.what())));
    }
    // YAML refuses tabs in some places where JSON allows them; they are plain whitespace
    // in JSON outside strings, and inside strings JSON requires them escaped.
    std::replace(content.begin(), content.end(), '\t', ' ');
  } else if (ext != ".yaml" && ext != ".yml") {
    throw InputError(fmt::format("{}: a manifest must be .yaml, .yml or .json (got '{}')", file, ext));
  }
  return parse_yaml_text(content, file, ext == ".json" ? "JSON syntax error" : "YAML syntax error");
}

SegmentationSettings parse_segmentation(const Ctx& ctx, const ConfigSection& seg) {
  SegmentationSettings s;
  if (const auto m = seg.optional<std::string>("method")) {
    if (*m == "otsu") {
      s.method = SegmentationSettings::Method::kOtsu;
    } else if (*m == "global") {
      s.method = SegmentationSettings::Method::kGlobal;
    } else if (*m == "adaptive") {
      s.method = SegmentationSettings::Method::kAdaptive;
    } else if (*m == "background") {
      s.method = SegmentationSettings::Method::kBackground;
    } else {
      seg.fail_at("method",
                  fmt::format("'method': unknown segmentation method '{}' (otsu, global, adaptive or background)", *m));
    }
  }
  const auto whole = [&](const char* key, int fallback) {
    const auto v = seg.optional_value(key);
    return v ? whole_number(*v) : fallback;
  };
  s.channel = seg.get("channel", s.channel);
  s.threshold = seg.get("threshold", s.threshold);
  s.adaptive_block_px = whole("adaptive_block_px", s.adaptive_block_px);
  s.adaptive_offset = seg.get("adaptive_offset", s.adaptive_offset);
  if (const auto bg = seg.optional_value("background")) s.background = existing_file(ctx, *bg);
  s.background_difference = seg.get("background_difference", s.background_difference);
  s.object_darker = seg.get("object_darker", s.object_darker);
  s.blur_sigma_px = seg.get("blur_sigma_px", s.blur_sigma_px);
  s.open_radius_px = whole("open_radius_px", s.open_radius_px);
  s.close_radius_px = whole("close_radius_px", s.close_radius_px);
  s.largest_component = seg.get("largest_component", s.largest_component);
  s.min_component_px = seg.get("min_component_px", s.min_component_px);
  s.fill_holes = seg.get("fill_holes", s.fill_holes);
  s.min_contrast = seg.get("min_contrast", s.min_contrast);
  // The problem starts with the field's name; point at that field if it was given.
  if (const std::string problem = detail::segmentation_settings_problem(s); !problem.empty())
    seg.fail_at(problem.substr(0, problem.find(':')), problem);
  return s;
}

cv::Rect parse_roi(const ConfigValue& v) {
  if (!v.is_sequence() || v.items().size() != 4) v.fail("must be a list of 4 integers [x, y, width, height]");
  const std::vector<ConfigValue> xywh = v.items();
  const int x = whole_number(xywh[0]), y = whole_number(xywh[1]), w = whole_number(xywh[2]), h = whole_number(xywh[3]);
  if (x < 0 || y < 0) v.fail(fmt::format("x and y must be >= 0 (got {}, {})", x, y));
  if (w <= 0 || h <= 0) v.fail(fmt::format("width and height must be positive (got {}, {})", w, h));
  return cv::Rect(x, y, w, h);
}

struct FrameEntry {
  fs::path image;
  std::optional<double> time_s;
  ConfigValue node;  ///< the list item (or the glob) it comes from, for messages
};

/// Every file in the folder matching the last component of `pattern`, sorted by name.
std::vector<FrameEntry> glob_frames(const Ctx& ctx, const ConfigValue& glob) {
  const std::string pattern = path_text(glob);
  const fs::path full = ctx.resolve(pattern);
  const fs::path folder = full.parent_path();
  const std::string name_pattern = full.filename().string();
  if (folder.string().find_first_of("*?[") != std::string::npos)
    glob.fail(fmt::format("wildcards are allowed only in the file name (got '{}')", pattern));
  if (name_pattern.empty()) glob.fail(fmt::format("'{}' names no files", pattern));
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) glob.fail(fmt::format("folder {} does not exist", folder.string()));
  std::vector<fs::path> matches;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (::fnmatch(name_pattern.c_str(), name.c_str(), FNM_PERIOD) != 0) continue;
    std::error_code ec2;
    if (it->is_regular_file(ec2)) matches.push_back(it->path());
  }
  if (ec) glob.fail(fmt::format("cannot list {}: {}", folder.string(), ec.message()));
  if (matches.empty()) glob.fail(fmt::format("'{}' matches no file", pattern));
  std::sort(matches.begin(), matches.end(),
            [](const fs::path& a, const fs::path& b) { return a.filename().string() < b.filename().string(); });
  std::vector<FrameEntry> out;
  for (const auto& m : matches) out.push_back({m.lexically_normal(), std::nullopt, glob});
  return out;
}

std::vector<FrameEntry> parse_frames(const Ctx& ctx, const ConfigValue& n) {
  if (n.is_map()) {
    const ConfigSection g = n.section();
    if (!g.has("glob")) g.fail("must be a list of frames or {glob: pattern}");
    return glob_frames(ctx, g.value("glob"));
  }
  if (!n.is_sequence()) n.fail("must be a list of frames or {glob: pattern}");
  const std::vector<ConfigValue> items = n.items();
  if (items.empty()) n.fail("is empty");
  std::vector<FrameEntry> out;
  for (const ConfigValue& f : items) {
    if (f.is_scalar()) {
      out.push_back({ctx.resolve(path_text(f)), std::nullopt, f});
      continue;
    }
    const ConfigSection frame = f.section();
    if (!frame.has("image")) frame.fail("frame without 'image'");
    out.push_back({ctx.resolve(path_text(frame.value("image"))), frame.optional<double>("time_s"), f});
  }
  return out;
}

}  // namespace

ObservationSequence load_observations(const fs::path& manifest) {
  Ctx ctx;
  ctx.file = manifest.string();
  std::error_code ec;
  const fs::path absolute = fs::absolute(manifest, ec).lexically_normal();
  ctx.dir = absolute.parent_path();

  const ConfigValue doc(load_yaml(manifest, ctx.file), ctx.file);
  if (!doc.is_map()) doc.fail("a manifest must be a mapping of keys (meltlab_observations: 1, frames: ...)");
  const ConfigSection root = doc.section();
  if (!root.has("meltlab_observations")) root.fail("missing key 'meltlab_observations' (format version, 1)");
  if (const ConfigValue v = root.value("meltlab_observations"); v.scalar() != "1")
    v.fail(fmt::format("unsupported format version '{}' (this is version 1)", v.is_scalar() ? v.scalar() : "?"));
  if (root.has("mass_series") && root.has("volume_series"))
    root.fail_at("volume_series", "give either 'mass_series' or 'volume_series', not both");
  const char* series_key = root.has("volume_series") ? "volume_series" : "mass_series";
  const bool weighing_only = !root.has("frames") && root.has(series_key);
  if (!root.has("frames") && !weighing_only)
    root.fail("missing key 'frames' (the photos; a weighing experiment without photos names a mass_series instead)");
  if (!weighing_only && !root.has("camera")) root.fail("missing key 'camera'");
  if (weighing_only) {
    // Keys that only photos need: refused rather than ignored (a typo'd 'frames' would
    // otherwise silently turn a photo manifest into a weighing one).
    for (const char* key : {"camera", "roi", "segmentation"})
      if (root.has(key))
        root.fail_at(key,
                     fmt::format("'{}' without 'frames': a manifest of a mass series alone needs no {}", key, key));
  }

  ObservationSequence seq;
  seq.manifest = absolute;
  seq.object = root.get("object", seq.object);
  if (const auto dt = root.optional<double>("interval_s")) {
    if (*dt <= 0) root.fail_at("interval_s", fmt::format("'interval_s' must be positive (got {})", *dt));
    seq.interval_s = dt;
  }
  const std::optional<double> first_time = root.optional<double>("first_time_s");
  if (!weighing_only) seq.camera = render::parse_camera(root.section("camera"));
  if (const auto roi = root.optional_value("roi")) seq.roi = parse_roi(*roi);
  const std::optional<ConfigSection> segmentation = root.optional_section("segmentation");
  if (segmentation) seq.segmentation = parse_segmentation(ctx, *segmentation);
  if (const auto v = root.optional_value("ground_truth")) seq.ground_truth = existing_file(ctx, *v);
  if (const auto v = root.optional_value(series_key)) seq.mass_series = existing_file(ctx, *v);
  if (weighing_only) {
    root.finish();
    return seq;
  }
  const ConfigValue frames_node = root.value("frames");
  const std::vector<FrameEntry> entries = parse_frames(ctx, frames_node);
  root.finish();

  // Frames.
  std::set<fs::path> seen;
  std::optional<double> previous_time;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const FrameEntry& e = entries[i];
    if (!seen.insert(e.image).second) e.node.fail(fmt::format("{} is listed twice", e.image.string()));
    Frame f;
    f.index = static_cast<int>(i);
    f.image = e.image;
    if (e.time_s) {
      f.time_s = e.time_s;
    } else if (seq.interval_s) {
      f.time_s = first_time.value_or(0.0) + static_cast<double>(i) * *seq.interval_s;
    } else if (i == 0 && first_time) {
      f.time_s = first_time;
    }
    if (f.time_s) {
      if (previous_time && !(*f.time_s > *previous_time)) {
        e.node.fail(fmt::format("frame {} ({}) has time_s {} s, not after the previous frame's {} s", i,
                                e.image.filename().string(), *f.time_s, *previous_time));
      }
      previous_time = f.time_s;
    }
    seq.frames.push_back(std::move(f));
  }

  // The first readable frame fixes the image size (for the ROI, the camera, the background).
  std::optional<cv::Size> size;
  std::string first_problem;
  std::size_t existing = 0;
  for (const Frame& f : seq.frames) {
    std::error_code ec2;
    if (!fs::exists(f.image, ec2)) continue;
    ++existing;
    try {
      size = detail::read_image_size(f.image);
      break;
    } catch (const InputError& err) {
      if (first_problem.empty()) first_problem = err.what();
    }
  }
  if (existing == 0) {
    frames_node.fail(
        fmt::format("none of the {} frames exists (first: {})", seq.frames.size(), seq.frames.front().image.string()));
  }
  if (!size) frames_node.fail(fmt::format("no frame is a readable image ({})", first_problem));
  const int cam_w = render::camera_width(seq.camera), cam_h = render::camera_height(seq.camera);
  if (cam_w != size->width || cam_h != size->height) {
    root.fail_at("camera", fmt::format("'camera': renders {}x{} but the frames are {}x{}", cam_w, cam_h, size->width,
                                       size->height));
  }
  if (seq.roi && (*seq.roi & cv::Rect(0, 0, size->width, size->height)) != *seq.roi) {
    root.fail_at("roi", fmt::format("'roi' [{}, {}, {}, {}] is outside the {}x{} frames", seq.roi->x, seq.roi->y,
                                    seq.roi->width, seq.roi->height, size->width, size->height));
  }
  if (!seq.segmentation.background.empty()) {
    cv::Size bg_size;
    try {
      bg_size = detail::read_image_size(seq.segmentation.background);
    } catch (const InputError& err) {
      segmentation->fail_at("background", fmt::format("'background': {}", err.what()));
    }
    if (bg_size != *size) {
      segmentation->fail_at("background", fmt::format("'background' is {}x{} but the frames are {}x{}", bg_size.width,
                                                      bg_size.height, size->width, size->height));
    }
  }
  return seq;
}

}  // namespace meltlab::verify
