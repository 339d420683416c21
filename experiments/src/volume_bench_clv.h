#pragma once
// Seed 001's studies of `meltlab volume bench` (volume_bench.h), one function per --study:
//   seed001-generate  generator throughput (batched parallel against the naive writer), file
//                     sizes against the spec's arithmetic, occupancy of the cached volumes
//   seed001-tables    Tables 5.1 (samples per image on the skull phantom; per-pixel counts),
//                     5.2 (single-thread time by method, RAM and mmap, cold first frame) and 5.4
//                     (float32 samples)
//   seed001-large     Table 5.3 (single thread none and optimised in RAM; multi-thread object
//                     order on the blocked file, memory-mapped)
//   seed001-sweeps    tile side, block side and render-thread count of the object-order renderer
//   seed001-peer      OpenVDB's VolumeRender on the same volume with the TF as extinction
//   seed001-steps     Fig. 5.2: steps 0.1-0.9 against a 0.05 reference
//   seed001-ess       one-level against multi-level skipping over the 8 orbit poses
// The volumes come from the data cache (datasets::default_cache_dir()/clv), generated on first use.

#include <meltlab/experiments/volume_bench.h>

#include <nlohmann/json.hpp>

#include <filesystem>

namespace meltlab::experiments::clv_bench {

void study_generate(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_tables(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_large(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_sweeps(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_peer(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_steps(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);
void study_ess(const VolumeBenchOptions& o, const std::filesystem::path& dir, nlohmann::json& record);

}  // namespace meltlab::experiments::clv_bench
