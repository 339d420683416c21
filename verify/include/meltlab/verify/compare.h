#pragma once
// Comparison of a simulated melt with an observed photo sequence (monograph chapter 8):
// for every photo, the simulated mesh at the matching cycle is rendered with the photo's
// camera, registered onto the photo's contour, and compared (P of Eq. 8.1 on pixels and on
// exact polygon areas, IoU, Dice, Hausdorff and mean contour distance in pixels and mm).
// A frame whose photo is missing, unreadable or segments to nothing is reported and
// skipped — never counted as P = 0 or 1.

#include <meltlab/render/raster/silhouette.h>
#include <meltlab/sim/mesh.h>
#include <meltlab/sim/mesh_sequence.h>
#include <meltlab/verify/metrics.h>
#include <meltlab/verify/observations.h>
#include <meltlab/verify/registration.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::verify {

/// The time scale when none is given: the monograph's photographed melts run ~700 simulation
/// cycles per 100 photos (§8.2). Written once here; the fit, the comparison, the synthetic
/// sequences and the CLI defaults all use it.
inline constexpr double kDefaultCyclesPerPhoto = 7.0;

/// Which cycle shows the state of photo k (0-based): either k photos × K cycles, or the
/// photo's time divided by the seconds per cycle (monograph §9.4: ~7 cycles per 40 s photo).
struct FrameMapping {
  std::optional<double> cycles_per_photo;   ///< K (kDefaultCyclesPerPhoto when neither is set)
  std::optional<double> seconds_per_cycle;  ///< S (needs frame times)
  double first_cycle = 0;                   ///< cycle of photo 0 (t = 0)
  /// The cycle of a frame (rounded to the nearest); throws InputError if times are needed
  /// and the frame has none.
  std::int64_t cycle_of(const Frame& f, const std::string& manifest) const;
};

enum class RegistrationMode {
  kNone,        ///< compare as rendered
  kFirstFrame,  ///< estimate on the first usable frame, keep it for the whole sequence (default)
  kEveryFrame,  ///< estimate for every frame
  kGiven,       ///< use CompareOptions::given_registration for every frame
};

struct CompareOptions {
  FrameMapping mapping;
  RegistrationMode registration = RegistrationMode::kFirstFrame;
  RegistrationOptions registration_options;
  Similarity2D given_registration;
  int supersample = 4;           ///< of the rendered silhouette used for the exact (polygon) P
  bool exact = true;             ///< also compute P from sub-pixel polygons with CGAL
  std::int64_t last_cycle = -1;  ///< frames mapped beyond this cycle are skipped (-1: no limit)
};

struct FrameResult {
  int frame = 0;      ///< 0-based index in the sequence
  std::string image;  ///< file name
  std::optional<double> time_s;
  std::int64_t cycle = 0;
  std::string status = "ok";  ///< ok | missing | unreadable | empty_photo | beyond_run
  std::string note;           ///< why a frame was skipped
  AreaComparison pixels;      ///< S_A, S_B, S_I, P, IoU, Dice on pixel counts
  std::optional<double> P_exact;
  ContourDistances distances_px;
  double mm_per_px = 0;       ///< at the ground plane (0 if unknown)
  Similarity2D registration;  ///< render -> photo transform used
  double render_area_px = 0;
  double photo_area_px = 0;
};

struct CompareResult {
  std::vector<FrameResult> frames;
  int compared = 0;
  int skipped = 0;
  std::optional<Similarity2D> registration;  ///< the fixed one, for kFirstFrame/kGiven
  double registration_P_before = 1, registration_P_after = 1;
};

/// Per-frame images the caller may keep (overlays).
struct FrameImages {
  cv::Mat photo_mask, render_mask;  ///< in photo coordinates (render registered)
};

/// Runs the comparison. `on_frame` (optional) is called after every frame with its result
/// and masks (e.g. to write overlays and show progress).
CompareResult compare_sequence(const ObservationSequence& observations, sim::MeshSequence& meshes,
                               const CompareOptions& options,
                               const std::function<void(const FrameResult&, const FrameImages&)>& on_frame = {});

/// The overlay of the monograph's Fig. 8.12: photo only dark grey, render only black,
/// common light grey, background white (CV_8UC1).
cv::Mat overlay_image(const cv::Mat& photo_mask, const cv::Mat& render_mask);

/// A line chart of P against photo number (1-based) like Figs. 8.7–8.10, with the
/// acceptance threshold P = 0.2 drawn dashed (CV_8UC3, drawn with OpenCV).
cv::Mat p_curve_image(const std::vector<FrameResult>& frames, const std::string& title);

/// Writes per_frame.csv (frame, image, status, time_s, cycle, S_A, S_B, S_I, P, P_exact,
/// IoU, Dice, Hausdorff_px, Hausdorff_mm, mean_distance_px, mean_distance_mm, and the
/// registration) atomically.
void write_per_frame_csv(const std::filesystem::path& file, const std::vector<FrameResult>& frames);

}  // namespace meltlab::verify
