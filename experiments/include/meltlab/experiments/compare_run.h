#pragma once
// `meltlab compare`: compares a simulate run with an observed photo sequence (monograph
// chapter 8) and writes the comparison folder
//   DIR/per_frame.csv      one row per photo: P on pixels and exact areas, IoU, Dice,
//                          Hausdorff and mean contour distance (px, mm), registration, status
//   DIR/overlays/*.png     Fig. 8.12 overlays (photo only dark grey, render only black,
//                          common light grey) of every K-th compared frame
//   DIR/p_curve.png        P against photo number (Figs. 8.7-8.10)
//   DIR/compare.json       options, inputs (with hashes), summary (P_first, P_last, P_max,
//                          mean, frames compared/skipped), registration, timings, provenance
// Every input is validated before DIR is touched; every file is written atomically and
// compare.json, written last, marks a finished comparison.

#include <meltlab/verify/compare.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct CompareRunOptions {
  std::filesystem::path run_dir;       ///< a `meltlab simulate` output folder
  std::filesystem::path observations;  ///< manifest (.yaml/.yml/.json)
  std::filesystem::path out_dir;
  verify::CompareOptions compare;
  int overlay_every = 1;                  ///< write the overlay of every K-th compared frame (0 = none)
  bool overwrite = false;                 ///< allow DIR to hold a previous comparison
  std::vector<std::string> command_line;  ///< argv, recorded in the provenance of the run record
};

struct CompareRunProgress {
  int done = 0, total = 0;
  double last_P = 0;
  int skipped = 0;
};

struct CompareRunResult {
  verify::CompareResult compare;
  nlohmann::json summary;
};

/// Runs the comparison and writes DIR. Throws InputError on bad input (before writing).
CompareRunResult run_compare(const CompareRunOptions& options,
                             const std::function<void(const CompareRunProgress&)>& progress);

/// Compares and writes per_frame.csv, overlays/ (every K-th compared frame) and
/// p_curve.png into `out_dir` (created). `frame_ms` (optional) receives the time per frame.
verify::CompareResult compare_and_write(const verify::ObservationSequence& observations, sim::MeshSequence& meshes,
                                        const verify::CompareOptions& options, const std::filesystem::path& out_dir,
                                        int overlay_every,
                                        const std::function<void(const CompareRunProgress&)>& progress,
                                        std::vector<double>* frame_ms = nullptr);

/// Summary statistics of per-frame results (over frames with status ok): count, P of the
/// first and last compared frames, max, mean, the frame of the max, and the fraction of
/// frames with P <= 0.2 (the monograph's acceptance level).
nlohmann::json summarize_frames(const std::vector<verify::FrameResult>& frames);

}  // namespace meltlab::experiments
