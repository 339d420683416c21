#pragma once
// `meltlab volume bench`: the timing and accuracy studies of the volume ray caster (seed 000),
// written as CSV for the report (report/experiments/volume.py):
//   tables.csv   Tables 5.1-5.3 of the source on this CPU: Emission, HG, HGAttenuated (the
//                source's shadow march) and HGAttenuated with the shadow cache, at 64³/128³,
//                512²/256², 50/64/100 samples per ray: median frame time (warm-up frames first).
//   scaling.csv  time against the sample count n (50, 64, 100, 200), the number of lights (0..8)
//                and the pixel count: the spec's targets 9, 10 and 12.
//   pareto.csv   time against error for every knob (samples per ray, shadow step, shadow cache
//                resolution, ERT threshold, jitter, quadrature) against a reference of n = 1024 with
//                the exact shadow march (HGAttenuated on the sphere turbulence).
//   peer.csv     OpenVDB's tools::VolumeRender on the same volume (a FloatGrid), camera, light,
//                steps and extinction (isotropic phase) beside ours (shadow march and shadow cache):
//                time per frame, error against a fine reference, and the difference between the two.
//   bench.json   the scenes, the machine, and the run's provenance.
// Quick mode uses smaller images for the studies that need a brute-force reference.
//
// Seed 001 (CPU rendering of large volumes; the studies named seed001-*, run only when asked):
//   generate.csv, sizes.csv  the generator's throughput, batched and naive; file sizes against the
//                            spec's arithmetic; occupancy of the generated volumes
//   tables.csv, counts/      Tables 5.1, 5.2, 5.4 (samples, single-thread time by method, RAM and
//                            mmap, float32), per-pixel sample counts (16-bit PNG) for Fig. 5.1
//   large.csv                Table 5.3 (the 2000³ volume in full mode; 800³ at 350² in quick)
//   sweeps.csv               tile side, block side, render threads of the object-order renderer
//   peer.csv                 OpenVDB's VolumeRender with the TF as extinction beside ours
//   steps.csv                Fig. 5.2: steps 0.1-0.9 against 0.05
//   ess.csv                  one-level against multi-level empty-space skipping over 8 poses
// Their volumes are generated once into the data cache (MELTLAB_DATA_DIR/clv).
//
// Seed 003 (view-aligned slicing with a mask and four TFs; studies seed003-*, on the scenes of
// --slicing-scenes, see volume_bench_slicing.h):
//   slicing_figures.csv, slicing_figures/  every scene in Blend, MIP and combined, without and with bloom
//   slicing_table3.csv      Table 3: time per frame against QC, Blend and combined; coverage
//   slicing_table4.csv      Table 4: ns per sample against data size at a constant slice count
//   slicing_pareto.csv, slicing_costs.csv  slicing against the ray caster at equal sample density (RMSE against a
//                           fine ray-cast reference); the mask lookup's and bloom's cost

#include <filesystem>
#include <string>
#include <vector>

namespace meltlab::experiments {

struct VolumeBenchOptions {
  std::vector<std::string> studies{"tables", "scaling", "pareto", "peer"};
  bool quick = true;
  int warmup = 1, repeats = 3;  ///< frames before timing, timed frames (the median is reported)
  int large_size = 0;           ///< seed001-large: N of the N³ volume (0: 800 quick, 2000 full)
  /// seed003-*: scene files with method: slicing (the first is the reference for Tables 3, 4 and
  /// the Pareto study); seed003-table4: volume sizes "NXxNYxNZ" (empty: the source's list).
  std::vector<std::filesystem::path> slicing_scenes;
  std::vector<std::string> table4_sizes;
  /// seed003-table3: the quality classes timed (empty: the source's 13, 0.2 ... 7; full adds 8).
  std::vector<double> table3_qcs;
  std::filesystem::path out_dir;
  bool overwrite = false;
  std::vector<std::string> command_line;
};

/// Runs the studies into the run folder (progress on stderr). Throws InputError for bad options.
void run_volume_bench(const VolumeBenchOptions& options);

}  // namespace meltlab::experiments
