// Reading observation manifests (observations.h).
//
// YAML and JSON manifests go through the same code: JSON is first checked with
// nlohmann::json (JSON syntax errors with their line), then loaded with yaml-cpp (YAML is a
// superset of JSON), which keeps the line of every node for messages. Every message is one
// line, "<manifest>:<line>: <problem>", naming the key concerned.
//
// Choices where observations.h leaves room:
//  - `camera` is required (the comparison renders the simulation with it); its width and
//    height must equal the first readable frame's size.
//  - frame times: an explicit time_s wins; otherwise first_time_s + index * interval_s when
//    interval_s is given; otherwise the first frame gets first_time_s if that is given, and
//    other frames have no time. Known times must strictly increase.
//  - a frame entry is {image: path, time_s: t} or just a path string.
//  - glob: wildcards (* ? [..]) only in the last path component; sorted by file name.
//  - ground_truth, mass_series and segmentation.background must exist (their errors are
//    better found here than half-way through a comparison); the background must be a
//    readable image of the frames' size.
//  - duplicate keys in a mapping are errors.

#include "obs_detail.h"

#include <meltlab/core/yaml_keys.h>
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

/// Context for messages: the manifest's name as given.
struct Ctx {
  std::string file;
  fs::path dir;  ///< absolute folder of the manifest

  std::string at(const YAML::Node& n) const {
    const YAML::Mark m = n.Mark();
    if (m.line >= 0) return fmt::format("{}:{}", file, m.line + 1);
    return file;
  }
  std::string at(const YAML::Mark& m) const {
    if (m.line >= 0) return fmt::format("{}:{}", file, m.line + 1);
    return file;
  }
  [[noreturn]] void fail(const YAML::Node& n, const std::string& problem) const {
    throw InputError(fmt::format("{}: {}", at(n), problem));
  }
  fs::path resolve(const std::string& p) const {
    const fs::path path(p);
    return (path.is_absolute() ? path : dir / path).lexically_normal();
  }
};

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

/// Checks that `n` is a mapping whose keys are all in `allowed` and not repeated.
/// Returns the key nodes by name (for the line of a key).
std::vector<std::pair<std::string, YAML::Node>> checked_map(const Ctx& ctx, const YAML::Node& n,
                                                            const std::string& what,
                                                            const std::vector<std::string>& allowed) {
  if (!n.IsMap()) ctx.fail(n, fmt::format("'{}' must be a mapping of keys", what));
  std::vector<std::pair<std::string, YAML::Node>> keys;
  std::set<std::string> seen;
  for (auto it = n.begin(); it != n.end(); ++it) {
    if (!it->first.IsScalar()) ctx.fail(it->first, fmt::format("keys of '{}' must be names", what));
    const std::string k = it->first.Scalar();
    if (std::find(allowed.begin(), allowed.end(), k) == allowed.end()) {
      ctx.fail(it->first, fmt::format("unknown key '{}' in {} (allowed: {})", k, what, join(allowed)));
    }
    if (!seen.insert(k).second) ctx.fail(it->first, fmt::format("key '{}' appears twice in {}", k, what));
    keys.emplace_back(k, it->first);
  }
  return keys;
}

double number(const Ctx& ctx, const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) ctx.fail(n, fmt::format("'{}' must be a number", key));
  double x = 0;
  try {
    x = n.as<double>();
  } catch (const YAML::Exception&) {
    ctx.fail(n, fmt::format("'{}' must be a number (got '{}')", key, n.Scalar()));
  }
  if (!std::isfinite(x)) ctx.fail(n, fmt::format("'{}' must be a finite number (got '{}')", key, n.Scalar()));
  return x;
}

int integer(const Ctx& ctx, const YAML::Node& n, const std::string& key) {
  const double x = number(ctx, n, key);
  if (x != std::floor(x) || std::abs(x) > 1e9) {
    ctx.fail(n, fmt::format("'{}' must be an integer (got '{}')", key, n.Scalar()));
  }
  return static_cast<int>(x);
}

bool boolean(const Ctx& ctx, const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) ctx.fail(n, fmt::format("'{}' must be true or false", key));
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    ctx.fail(n, fmt::format("'{}' must be true or false (got '{}')", key, n.Scalar()));
  }
}

std::string text(const Ctx& ctx, const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) ctx.fail(n, fmt::format("'{}' must be a text value", key));
  return n.Scalar();
}

std::string path_text(const Ctx& ctx, const YAML::Node& n, const std::string& key) {
  std::string s = text(ctx, n, key);
  if (s.empty()) ctx.fail(n, fmt::format("'{}' must be a non-empty path", key));
  return s;
}

fs::path existing_file(const Ctx& ctx, const YAML::Node& n, const std::string& key) {
  const fs::path p = ctx.resolve(path_text(ctx, n, key));
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) {
    ctx.fail(n, fmt::format("'{}': {} {}", key, p.string(), fs::exists(p, ec) ? "is not a file" : "does not exist"));
  }
  return p;
}

YAML::Node load_yaml(const fs::path& manifest, const std::string& file) {
  std::error_code ec;
  if (fs::is_directory(manifest, ec)) throw InputError(fmt::format("{}: is a directory, not a manifest", file));
  std::string content = read_text_file(manifest, "manifest");
  if (content.find_first_not_of(" \t\r\n") == std::string::npos) throw InputError(fmt::format("{}: empty manifest", file));

  std::string ext = manifest.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
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
  try {
    YAML::Node root = YAML::Load(content);
    return root;
  } catch (const YAML::Exception& e) {
    throw yaml_error(file, e, ext == ".json" ? "JSON syntax error" : "YAML syntax error");
  }
}

SegmentationSettings parse_segmentation(const Ctx& ctx, const YAML::Node& n) {
  static const std::vector<std::string> kKeys = {
      "method",         "channel",          "threshold",     "adaptive_block_px", "adaptive_offset",
      "background",     "background_difference", "object_darker", "blur_sigma_px", "open_radius_px",
      "close_radius_px", "largest_component", "min_component_px", "fill_holes", "min_contrast"};
  const auto keys = checked_map(ctx, n, "segmentation", kKeys);
  SegmentationSettings s;
  for (const auto& [key, key_node] : keys) {
    const YAML::Node v = n[key];
    if (key == "method") {
      const std::string m = text(ctx, v, key);
      if (m == "otsu") {
        s.method = SegmentationSettings::Method::kOtsu;
      } else if (m == "global") {
        s.method = SegmentationSettings::Method::kGlobal;
      } else if (m == "adaptive") {
        s.method = SegmentationSettings::Method::kAdaptive;
      } else if (m == "background") {
        s.method = SegmentationSettings::Method::kBackground;
      } else {
        ctx.fail(v, fmt::format("'method': unknown segmentation method '{}' (otsu, global, adaptive or background)", m));
      }
    } else if (key == "channel") {
      s.channel = text(ctx, v, key);
    } else if (key == "threshold") {
      s.threshold = number(ctx, v, key);
    } else if (key == "adaptive_block_px") {
      s.adaptive_block_px = integer(ctx, v, key);
    } else if (key == "adaptive_offset") {
      s.adaptive_offset = number(ctx, v, key);
    } else if (key == "background") {
      s.background = existing_file(ctx, v, key);
    } else if (key == "background_difference") {
      s.background_difference = number(ctx, v, key);
    } else if (key == "object_darker") {
      s.object_darker = boolean(ctx, v, key);
    } else if (key == "blur_sigma_px") {
      s.blur_sigma_px = number(ctx, v, key);
    } else if (key == "open_radius_px") {
      s.open_radius_px = integer(ctx, v, key);
    } else if (key == "close_radius_px") {
      s.close_radius_px = integer(ctx, v, key);
    } else if (key == "largest_component") {
      s.largest_component = boolean(ctx, v, key);
    } else if (key == "min_component_px") {
      s.min_component_px = number(ctx, v, key);
    } else if (key == "min_contrast") {
      s.min_contrast = number(ctx, v, key);
    } else if (key == "fill_holes") {
      s.fill_holes = boolean(ctx, v, key);
    }
  }
  if (const std::string problem = detail::segmentation_settings_problem(s); !problem.empty()) {
    // The problem starts with the field's name; point at that field if it was given.
    const std::string field = problem.substr(0, problem.find(':'));
    const YAML::Node v = n[field];
    ctx.fail(v ? v : n, fmt::format("segmentation.{}", problem));
  }
  return s;
}

std::optional<cv::Rect> parse_roi(const Ctx& ctx, const YAML::Node& n) {
  if (!n.IsSequence() || n.size() != 4) ctx.fail(n, "'roi' must be a list of 4 integers [x, y, width, height]");
  const int x = integer(ctx, n[0], "roi");
  const int y = integer(ctx, n[1], "roi");
  const int w = integer(ctx, n[2], "roi");
  const int h = integer(ctx, n[3], "roi");
  if (x < 0 || y < 0) ctx.fail(n, fmt::format("'roi': x and y must be >= 0 (got {}, {})", x, y));
  if (w <= 0 || h <= 0) ctx.fail(n, fmt::format("'roi': width and height must be positive (got {}, {})", w, h));
  return cv::Rect(x, y, w, h);
}

struct FrameEntry {
  fs::path image;
  std::optional<double> time_s;
  YAML::Node node;
};

/// Every file in the folder matching the last component of `pattern`, sorted by name.
std::vector<FrameEntry> glob_frames(const Ctx& ctx, const YAML::Node& glob_node) {
  const std::string pattern = path_text(ctx, glob_node, "glob");
  const fs::path full = ctx.resolve(pattern);
  const fs::path folder = full.parent_path();
  const std::string name_pattern = full.filename().string();
  if (folder.string().find_first_of("*?[") != std::string::npos) {
    ctx.fail(glob_node, fmt::format("'glob': wildcards are allowed only in the file name (got '{}')", pattern));
  }
  if (name_pattern.empty()) ctx.fail(glob_node, fmt::format("'glob': '{}' names no files", pattern));
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) {
    ctx.fail(glob_node, fmt::format("'glob': folder {} does not exist", folder.string()));
  }
  std::vector<fs::path> matches;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (::fnmatch(name_pattern.c_str(), name.c_str(), FNM_PERIOD) != 0) continue;
    std::error_code ec2;
    if (it->is_regular_file(ec2)) matches.push_back(it->path());
  }
  if (ec) ctx.fail(glob_node, fmt::format("'glob': cannot list {}: {}", folder.string(), ec.message()));
  if (matches.empty()) ctx.fail(glob_node, fmt::format("'glob': '{}' matches no file", pattern));
  std::sort(matches.begin(), matches.end(),
            [](const fs::path& a, const fs::path& b) { return a.filename().string() < b.filename().string(); });
  std::vector<FrameEntry> out;
  for (const auto& m : matches) out.push_back({m.lexically_normal(), std::nullopt, glob_node});
  return out;
}

std::vector<FrameEntry> parse_frames(const Ctx& ctx, const YAML::Node& n) {
  if (n.IsMap()) {
    checked_map(ctx, n, "frames", {"glob"});
    if (!n["glob"]) ctx.fail(n, "'frames' must be a list of frames or {glob: pattern}");
    return glob_frames(ctx, n["glob"]);
  }
  if (!n.IsSequence()) ctx.fail(n, "'frames' must be a list of frames or {glob: pattern}");
  if (n.size() == 0) ctx.fail(n, "'frames' is empty");
  std::vector<FrameEntry> out;
  for (const YAML::Node& f : n) {
    FrameEntry e;
    e.node = f;
    if (f.IsScalar()) {
      e.image = ctx.resolve(path_text(ctx, f, "image"));
    } else {
      checked_map(ctx, f, "frame", {"image", "time_s"});
      if (!f["image"]) ctx.fail(f, "frame without 'image'");
      e.image = ctx.resolve(path_text(ctx, f["image"], "image"));
      if (f["time_s"]) e.time_s = number(ctx, f["time_s"], "time_s");
    }
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

ObservationSequence load_observations_checked(const fs::path& manifest);

ObservationSequence load_observations(const fs::path& manifest) {
  try {
    return load_observations_checked(manifest);
  } catch (const YAML::Exception& e) {
    throw yaml_error(manifest.string(), e, "bad value");
  }
}

ObservationSequence load_observations_checked(const fs::path& manifest) {
  Ctx ctx;
  ctx.file = manifest.string();
  std::error_code ec;
  const fs::path absolute = fs::absolute(manifest, ec).lexically_normal();
  ctx.dir = absolute.parent_path();

  const YAML::Node root = load_yaml(manifest, ctx.file);
  static const std::vector<std::string> kKeys = {"meltlab_observations", "object", "frames",       "interval_s",
                                                 "first_time_s",         "camera", "roi",          "segmentation",
                                                 "ground_truth",         "mass_series"};
  if (!root.IsMap()) ctx.fail(root, "a manifest must be a mapping of keys (meltlab_observations: 1, frames: ...)");
  checked_map(ctx, root, "the manifest", kKeys);
  if (!root["meltlab_observations"]) ctx.fail(root, "missing key 'meltlab_observations' (format version, 1)");
  if (const YAML::Node v = root["meltlab_observations"]; !v.IsScalar() || v.Scalar() != "1") {
    ctx.fail(v, fmt::format("'meltlab_observations': unsupported format version '{}' (this is version 1)",
                            v.IsScalar() ? v.Scalar() : "?"));
  }
  if (!root["frames"]) ctx.fail(root, "missing key 'frames'");
  if (!root["camera"]) ctx.fail(root, "missing key 'camera'");

  ObservationSequence seq;
  seq.manifest = absolute;
  if (root["object"]) seq.object = text(ctx, root["object"], "object");
  if (root["interval_s"]) {
    const double dt = number(ctx, root["interval_s"], "interval_s");
    if (dt <= 0) ctx.fail(root["interval_s"], fmt::format("'interval_s' must be positive (got {})", dt));
    seq.interval_s = dt;
  }
  std::optional<double> first_time;
  if (root["first_time_s"]) first_time = number(ctx, root["first_time_s"], "first_time_s");

  // Camera: errors from parse_camera name the file; make sure they carry the line too.
  {
    const YAML::Node cam = root["camera"];
    try {
      seq.camera = render::parse_camera(cam, ctx.file);
    } catch (const InputError& e) {
      const std::string msg = e.what();
      const std::string prefix = ctx.file + ":";
      if (msg.rfind(prefix, 0) == 0 && msg.size() > prefix.size() && std::isdigit(static_cast<unsigned char>(msg[prefix.size()]))) {
        throw;
      }
      std::string rest = msg.rfind(ctx.file, 0) == 0 ? msg.substr(ctx.file.size()) : msg;
      if (rest.rfind(": ", 0) == 0) rest = rest.substr(2);
      ctx.fail(cam, fmt::format("'camera': {}", rest));
    } catch (const YAML::Exception& e) {
      ctx.fail(cam, fmt::format("'camera': {}", one_line(e.msg)));
    }
  }
  if (root["roi"]) seq.roi = parse_roi(ctx, root["roi"]);
  if (root["segmentation"]) seq.segmentation = parse_segmentation(ctx, root["segmentation"]);
  if (root["ground_truth"]) seq.ground_truth = existing_file(ctx, root["ground_truth"], "ground_truth");
  if (root["mass_series"]) seq.mass_series = existing_file(ctx, root["mass_series"], "mass_series");

  // Frames.
  const YAML::Node frames_node = root["frames"];
  const std::vector<FrameEntry> entries = parse_frames(ctx, frames_node);
  std::set<fs::path> seen;
  std::optional<double> previous_time;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const FrameEntry& e = entries[i];
    if (!seen.insert(e.image).second) {
      ctx.fail(e.node, fmt::format("'frames': {} is listed twice", e.image.string()));
    }
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
        ctx.fail(e.node, fmt::format("'time_s': frame {} ({}) has time {} s, not after the previous frame's {} s", i,
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
    ctx.fail(frames_node, fmt::format("'frames': none of the {} frames exists (first: {})", seq.frames.size(),
                                      seq.frames.front().image.string()));
  }
  if (!size) {
    ctx.fail(frames_node, fmt::format("'frames': no frame is a readable image ({})", first_problem));
  }
  const int cam_w = render::camera_width(seq.camera), cam_h = render::camera_height(seq.camera);
  if (cam_w != size->width || cam_h != size->height) {
    ctx.fail(root["camera"], fmt::format("'camera': renders {}x{} but the frames are {}x{}", cam_w, cam_h, size->width,
                                         size->height));
  }
  if (seq.roi && (*seq.roi & cv::Rect(0, 0, size->width, size->height)) != *seq.roi) {
    ctx.fail(root["roi"], fmt::format("'roi' [{}, {}, {}, {}] is outside the {}x{} frames", seq.roi->x, seq.roi->y,
                                      seq.roi->width, seq.roi->height, size->width, size->height));
  }
  if (!seq.segmentation.background.empty()) {
    const YAML::Node bg = root["segmentation"]["background"];
    cv::Size bg_size;
    try {
      bg_size = detail::read_image_size(seq.segmentation.background);
    } catch (const InputError& err) {
      ctx.fail(bg, fmt::format("'background': {}", err.what()));
    }
    if (bg_size != *size) {
      ctx.fail(bg, fmt::format("'background' is {}x{} but the frames are {}x{}", bg_size.width, bg_size.height,
                               size->width, size->height));
    }
  }
  return seq;
}

}  // namespace meltlab::verify
