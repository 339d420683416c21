#pragma once
// Seed 003's studies of `meltlab volume bench` (volume_bench.h; spec
// ../shared/spec/volume-slicing-importance.md §4, §5 targets 4-6), one function per --study, all on
// the scenes named by --slicing-scenes (method: slicing; the first is the reference set-up: its
// volume, camera, TFs and settings are those of Tables 3 and 4 and the Pareto study; the
// reproduce experiment passes the CT phantom with the three mask set-ups of the spec §3):
//   seed003-figures  every scene in Blend, MIP and combined, each written without bloom (the
//                    frame before the post chain) and with bloom (the chain on): slicing_figures/*.png
//   seed003-table3   time per frame against QC for Blend and combined (bloom off) at the scene's
//                    image size; the object's pixel coverage (slicing_table3.csv)
//   seed003-table4   time per sample against data size at a constant slice count: the phantom
//                    generated at each --sizes entry, placed in the same box, Blend with a TF
//                    visible everywhere, no mask, empty-space skipping off (slicing_table4.csv)
//   seed003-pareto   slicing Blend against the ray caster's TF model at equal sample density (one
//                    piecewise-constant TF, the kind the ray caster reads), RMSE against a fine
//                    ray-cast reference, per QC (slicing_pareto.csv); the cost of the mask lookup (none
//                    against an all-ones mask, the same image) and of bloom, as medians of
//                    interleaved repeats (slicing_costs.csv)

#include <meltlab/experiments/volume_bench.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

namespace meltlab::experiments::slicing_bench {

/// seed003-table3's quality classes: --qcs sorted, or the default grid; throws InputError for a value
/// outside the renderer's [0.01, 1000] or one given twice (run_volume_bench() calls it before any study).
std::vector<double> table3_qcs(const VolumeBenchOptions& o);

void study_figures(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_table3(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_table4(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_pareto(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);

}  // namespace meltlab::experiments::slicing_bench
