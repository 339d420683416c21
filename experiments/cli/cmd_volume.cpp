// meltlab volume: the volume renderers (seeds 000 and 001): generate the seeds' volumes, render a
// scene, describe a volume file, benchmark.

#include <meltlab/experiments/volume_bench.h>
#include <meltlab/experiments/volume_run.h>

#include <fmt/format.h>

#include <cstdio>

#include "cli_util.h"
#include "commands.h"

namespace meltlab::cli {

Run add_volume(CLI::App& app, const std::vector<std::string>& command_line) {
  auto* sub = app.add_subcommand("volume",
                                 "Volume rendering (seeds 000, 001: ray casting; 003: slicing with a mask): generate "
                                 "volumes, render scenes, describe files");
  sub->require_subcommand(1);

  // --- generate ---
  auto* gen = sub->add_subcommand("generate",
                                  "Write a generated volume: Perlin turbulence (box, sphere), fireball, constant; "
                                  "seed 001's shapes and skull phantom (.clv, streamed); seed 003's CT phantom "
                                  "(int16 .vlb or .nrrd)");
  auto g = std::make_shared<experiments::VolumeGenerateRunOptions>();
  auto kind = std::make_shared<std::string>("turbulence_box");
  auto size = std::make_shared<int>(64);
  auto clip = std::make_shared<std::string>("per_octave");
  auto falloff = std::make_shared<std::string>("linear");
  auto storage = std::make_shared<std::string>("float32");
  auto box = std::make_shared<std::vector<double>>();
  auto seed = std::make_shared<std::uint64_t>(0);
  auto dims = std::make_shared<std::vector<int>>();
  auto layout = std::make_shared<std::string>("linear");
  auto quiet = std::make_shared<bool>(false);
  gen->add_option("--kind", *kind, "turbulence_box, turbulence_sphere, fireball, constant, shapes, skull or ct_phantom")
      ->check(CLI::IsMember(
          {"turbulence_box", "turbulence_sphere", "fireball", "constant", "shapes", "skull", "ct_phantom"}))
      ->default_val("turbulence_box");
  gen->add_option("--size", *size, "Samples per axis (seed 000: 64 or 128; seed 001: 800 or 2000)")
      ->check(CLI::Range(1, 100000))
      ->default_val(64);
  gen->add_option("--dims", *dims,
                  "Samples per axis x,y,z (instead of --size; the skull's default: 256,256,68; ct_phantom's: "
                  "256,256,113)")
      ->delimiter(',')
      ->expected(3)
      ->check(CLI::Range(1, 100000));
  gen->add_option("--shapes", g->generate.shapes.count, "shapes: the number of cuboids and spheres K")
      ->check(CLI::Range(0, 1000000))
      ->default_val(70);
  gen->add_option("--sample", g->generate.shapes.sample, "shapes: values uniform on [sample - 10, sample + 10]")
      ->check(CLI::Range(10, 245))
      ->default_val(100);
  gen->add_option("--object-size", g->generate.shapes.object_size, "shapes: object size s (sides s ± s/3)")
      ->check(CLI::Range(1, 1 << 20))
      ->default_val(70);
  gen->add_option("--layout", *layout, ".clv: linear (slices, z fastest) or blocked")
      ->check(CLI::IsMember({"linear", "blocked"}))
      ->default_val("linear");
  gen->add_option("--block-side", g->block_side, ".clv blocked: the block side B (voxels)")
      ->check(CLI::Range(2, 255))
      ->default_val(16);
  gen->add_option("--batch", g->batch, ".clv: samples per batch (clv.gen.batch; 1: the naive writer)")
      ->check(CLI::Range(std::int64_t(1), std::int64_t(1) << 30))
      ->default_val(32768);
  gen->add_flag("--quiet", *quiet, "No progress lines");
  gen->add_option("--octaves", g->generate.noise.octaves, "Turbulence octaves (vlr.noise.octaves)")
      ->check(CLI::Range(1, 16))
      ->default_val(4);
  gen->add_option("--gain", g->generate.noise.gain, "Amplitude divisor per octave")->default_val(2.0);
  gen->add_option("--lacunarity", g->generate.noise.lacunarity, "Frequency factor per octave")->default_val(2.0);
  gen->add_option("--base-frequency", g->generate.noise.base_frequency, "Noise cells across the box at octave 0")
      ->default_val(4.0);
  gen->add_option("--clip", *clip, "per_octave (the source), sum_only or none")
      ->check(CLI::IsMember({"per_octave", "sum_only", "none"}))
      ->default_val("per_octave");
  gen->add_option("--seed", *seed,
                  "Turbulence: 0 = Perlin's reference table, else a seeded offset; shapes: the RNG seed (default 2); "
                  "skull: the noise seed (default 1)")
      ->default_val(0);
  gen->add_option("--falloff", *falloff, "Sphere variant: linear (1 - r/R) or none")
      ->check(CLI::IsMember({"linear", "none"}))
      ->default_val("linear");
  gen->add_option("--constant", g->generate.constant, "Value of --kind constant")->default_val(1.0);
  auto ct_spacing = std::make_shared<std::vector<double>>();
  gen->add_option("--spacing", *ct_spacing, "ct_phantom: voxel spacing x,y,z (default 1,1,2)")
      ->delimiter(',')
      ->expected(3);
  gen->add_option("--noise-hu", g->generate.ct.noise_sigma_hu, "ct_phantom: Gaussian noise sigma in HU (0: none)")
      ->check(CLI::Range(0.0, 1e4))
      ->default_val(20.0);
  gen->add_option("--quantization", *storage, "float32, uint8 or uint16 (vlr.data.quantization)")
      ->check(CLI::IsMember({"float32", "uint8", "uint16"}))
      ->default_val("float32");
  gen->add_option("--box", *box, "World box: cx,cy,cz,sx,sy,sz (default: the unit box [0,1]^3)")
      ->delimiter(',')
      ->expected(6);
  gen->add_option(
         "--out", g->out,
         "NAME.json (raw samples in NAME.raw beside it), NAME.vdb, NAME.clv (seed 001), NAME.vlb, NAME.nrrd or "
         "NAME.nhdr (seed 003)")
      ->required();
  gen->add_flag("--overwrite", g->overwrite, "Replace existing files");

  // --- render ---
  auto* ren = sub->add_subcommand(
      "render",
      "Render a volume scene (experiments/configs/volume/*.yaml; method: ray_casting or slicing) into a folder");
  auto r = std::make_shared<experiments::VolumeRenderRunOptions>();
  r->command_line = command_line;
  auto frames = std::make_shared<int>(0);
  auto samples = std::make_shared<int>(0);
  ren->add_option("--scene", r->scene_file,
                  "Scene YAML: model, volume, camera, sampling, optics, lights, shadow, output")
      ->required();
  ren->add_option("--out", r->out_dir, "Output folder (image.png, image.exr, render.json)")->required();
  ren->add_option("--width", r->width, "Image width (overrides the scene's; field of view kept)")->default_val(0);
  ren->add_option("--height", r->height, "Image height (overrides the scene's)")->default_val(0);
  ren->add_option("--frames", *frames, "Timed frames (overrides the scene's timing.frames)")->default_val(0);
  ren->add_option("--samples", *samples, "Samples per ray n (overrides the scene's sampling.n)")->default_val(0);
  ren->add_flag("--sample-counts", r->sample_counts,
                "transfer_function: write samples.png, the samples taken per pixel (16-bit)");
  ren->add_flag("--overwrite", r->overwrite, "Allow --out to hold a previous render");

  // --- info ---
  auto* info =
      sub->add_subcommand("info", "Describe a volume file (.json header, .vdb, .clv, .vlb, .nrrd, .nhdr) as JSON");
  auto info_file = std::make_shared<std::string>();
  info->add_option("file", *info_file, "Volume file")->required();

  // --- bench ---
  auto* bench = sub->add_subcommand("bench",
                                    "Timing and accuracy studies for the report (--study: seed 000 tables, scaling, "
                                    "pareto, peer; seed001-*; seed003-*)");
  auto b = std::make_shared<experiments::VolumeBenchOptions>();
  b->command_line = command_line;
  auto full = std::make_shared<bool>(false);
  bench
      ->add_option("--study", b->studies,
                   "tables, scaling, pareto, peer (seed 000; the default: all four); seed001-generate, "
                   "seed001-tables, seed001-large, seed001-sweeps, seed001-peer, seed001-steps, seed001-ess; "
                   "seed003-figures, seed003-table3, seed003-table4, seed003-pareto (need --slicing-scenes)")
      ->delimiter(',');
  bench
      ->add_option("--slicing-scenes", b->slicing_scenes,
                   "seed003-*: scene files with method: slicing, comma-separated (the first: Tables 3, 4, Pareto)")
      ->delimiter(',')
      ->check(CLI::ExistingFile);
  bench
      ->add_option("--sizes", b->table4_sizes,
                   "seed003-table4: volume sizes NXxNYxNZ, comma-separated (default: the source's 1³ (as 2³) ... "
                   "256x256x113; --full adds 512x512x226)")
      ->delimiter(',');
  bench
      ->add_option("--qcs", b->table3_qcs,
                   "seed003-table3: quality classes, comma-separated, each in [0.01, 1000] (default: the source's "
                   "0.2,0.4,0.8,1,1.5,2,2.5,3,3.5,4,5,6,7; --full adds 8)")
      ->delimiter(',');
  bench
      ->add_option("--large-size", b->large_size,
                   "seed001-large: the N of the N³ shapes volume (0: 800 quick, 2000 full)")
      ->default_val(0);
  bench->add_flag("--full", *full, "Full sizes (default: quick: smaller images for the brute-force references)");
  bench->add_option("--warmup", b->warmup, "Frames rendered before timing")->default_val(1);
  bench->add_option("--repeats", b->repeats, "Timed frames (the median is reported)")->default_val(3);
  bench->add_option("--out", b->out_dir, "Output folder (tables.csv, scaling.csv, pareto.csv, peer.csv, bench.json)")
      ->required();
  bench->add_flag("--overwrite", b->overwrite, "Allow --out to hold a previous bench");

  return [=]() {
    if (bench->parsed()) {
      b->quick = !*full;
      experiments::run_volume_bench(*b);
      std::fprintf(stderr, "meltlab: volume bench: wrote %s\n", b->out_dir.string().c_str());
      return kExitOk;
    }
    if (gen->parsed()) {
      g->generate.kind = render::parse_volume_kind(*kind, "--kind");
      g->generate.nx = g->generate.ny = g->generate.nz = *size;
      if (g->generate.kind == render::VolumeKind::kSkull && dims->empty() && !gen->count("--size")) {
        // Table 5.1's volume: 68 slices of 256 x 256 (z the slice axis).
        g->generate.nx = g->generate.ny = 256;
        g->generate.nz = 68;
      }
      if (g->generate.kind == render::VolumeKind::kCtPhantom) {
        if (dims->empty() && !gen->count("--size")) {
          // Seed 003's CT head: 113 slices of 256 x 256 at spacing 1:1:2.
          g->generate.nx = g->generate.ny = 256;
          g->generate.nz = 113;
        }
        g->generate.ct.seed = gen->count("--seed") ? *seed : 1;
        if (!ct_spacing->empty()) {
          g->generate.ct.spacing = Eigen::Vector3d((*ct_spacing)[0], (*ct_spacing)[1], (*ct_spacing)[2]);
          if (!(g->generate.ct.spacing.minCoeff() > 0) || !g->generate.ct.spacing.allFinite())
            throw InputError("--spacing: three finite numbers > 0");
        }
      } else if (!ct_spacing->empty() || gen->count("--noise-hu")) {
        throw InputError("--spacing, --noise-hu: options of --kind ct_phantom");
      }
      if (!dims->empty()) {
        g->generate.nx = (*dims)[0];
        g->generate.ny = (*dims)[1];
        g->generate.nz = (*dims)[2];
      }
      const bool seed001 =
          g->generate.kind == render::VolumeKind::kShapes || g->generate.kind == render::VolumeKind::kSkull;
      g->generate.shapes.seed = gen->count("--seed") ? *seed : (g->generate.kind == render::VolumeKind::kSkull ? 1 : 2);
      if (seed001 && g->out.extension() != ".clv" &&
          std::int64_t(g->generate.nx) * g->generate.ny * g->generate.nz > (std::int64_t(1) << 31))
        throw InputError("--out: a volume this large is written as a .clv file (streamed)");
      g->order = *layout == "blocked" ? render::ClvOrder::kBlocked : render::ClvOrder::kLinear;
      g->progress = !*quiet;
      g->generate.noise.clip = *clip == "per_octave" ? render::NoiseClip::kPerOctave
                               : *clip == "sum_only" ? render::NoiseClip::kSumOnly
                                                     : render::NoiseClip::kNone;
      g->generate.noise.seed = *seed;
      g->generate.falloff = *falloff == "none" ? render::SphereFalloff::kNone : render::SphereFalloff::kLinear;
      g->generate.storage = *storage == "uint8"    ? render::SampleType::kUint8
                            : *storage == "uint16" ? render::SampleType::kUint16
                                                   : render::SampleType::kFloat32;
      if (!box->empty()) {
        const Eigen::Vector3d c((*box)[0], (*box)[1], (*box)[2]), s((*box)[3], (*box)[4], (*box)[5]);
        if (!(s.minCoeff() > 0)) throw InputError("--box: the sides must be > 0");
        g->box = render::Box3{c - 0.5 * s, c + 0.5 * s};
      }
      const auto j = experiments::run_volume_generate(*g);
      std::printf("%s\n", j.dump(2).c_str());
      return kExitOk;
    }
    if (info->parsed()) {
      std::printf("%s\n", experiments::volume_info(*info_file).dump(2).c_str());
      return kExitOk;
    }
    if (*frames > 0) r->frames = *frames;
    if (*samples > 0) r->samples = *samples;
    const auto res = experiments::run_volume_render(*r);
    std::fprintf(stderr, "meltlab: volume render: %lld rays, %lld samples, median %.1f ms/frame; wrote %s\n",
                 static_cast<long long>(res.stats.rays), static_cast<long long>(res.stats.samples), res.median_frame_ms,
                 r->out_dir.string().c_str());
    return kExitOk;
  };
}

}  // namespace meltlab::cli
