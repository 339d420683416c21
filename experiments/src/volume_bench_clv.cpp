// `meltlab volume bench --study seed001-*`: seed 001's tables and studies (see volume_bench.h).

#include <meltlab/experiments/csv_table.h>
#include <meltlab/core/time.h>
#include <meltlab/core/statistics.h>
#include "volume_bench_clv.h"

#include <meltlab/core/atomic_file.h>
#include <meltlab/core/error.h>
#include <meltlab/core/image.h>
#include <meltlab/core/mapped_file.h>
#include <meltlab/datasets/catalog.h>
#include <meltlab/render/integrator/volume_integrator.h>
#include <meltlab/render/vdb/openvdb.h>
#include <meltlab/render/volume/clv_file.h>
#include <meltlab/render/volume/generate.h>
#include <meltlab/render/volume/shapes.h>

#include <fmt/format.h>
#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numbers>
#include <numeric>

namespace meltlab::experiments::clv_bench {

namespace fs = std::filesystem;
using nlohmann::json;
using render::BrickedVolume;
using render::ClvMemory;
using render::ClvOrder;
using render::Volume;
using render::VolumeFrame;
using render::VolumeRenderSettings;
using render::VolumeTracer;
using Vec3 = Eigen::Vector3d;

namespace {

void progress(const std::string& what) { std::fprintf(stderr, "meltlab: volume bench: %s\n", what.c_str()); }

double stddev(const std::vector<double>& v) {
  if (v.size() < 2) return 0;
  const double m = std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / double(v.size() - 1));
}

// ---- the seed's volumes in the data cache ---------------------------------------------------------

/// The spec's shapes parameters for an N³ volume: (70, 70) at 800, (140, 140) at 2000 (§3); other
/// sizes keep 70 shapes with the object size in proportion to 800.
render::ShapesOptions shapes_for(int n) {
  render::ShapesOptions o;
  o.dims = {n, n, n};
  o.seed = 2;
  o.sample = 100;
  if (n == 2000) {
    o.count = 140, o.object_size = 140;
  } else {
    o.count = 70, o.object_size = std::max(2, int(std::lround(70.0 * n / 800.0)));
  }
  return o;
}

/// The file of the shapes volume in the data cache (generated once: the name holds every parameter
/// and the generator's revision, so a changed generator never returns a stale file).
fs::path cached_shapes(int n, ClvOrder order, int side = 16) {
  const render::ShapesOptions o = shapes_for(n);
  const fs::path dir = datasets::default_cache_dir() / "clv";
  const fs::path file = dir / fmt::format("shapes-{}-k{}-s{}-v{}-seed{}-g1-{}.clv", n, o.count, o.object_size, o.sample,
                                          o.seed, order == ClvOrder::kBlocked ? fmt::format("b{}", side) : "linear");
  std::error_code ec;
  if (fs::exists(file, ec)) return file;
  fs::create_directories(dir, ec);
  progress(fmt::format("generating {} (once, into the data cache)", file.string()));
  render::ClvWriteOptions w;
  w.order = order;
  w.block_side = side;
  auto last = std::make_shared<int>(-1);
  w.progress = [last, file](std::int64_t done, std::int64_t total) {
    const int pct = int(100 * done / std::max<std::int64_t>(1, total));
    if (pct / 10 != *last / 10) {
      *last = pct;
      progress(fmt::format("  {} {} %", file.filename().string(), pct));
    }
  };
  render::write_clv_generated(file, o.dims, render::ShapesVolume(o), w);
  return file;
}

/// Pose p of the 8 fixed orbit poses (clv.camera.positions): azimuth 30° + 45° p, elevation ±25°
/// alternating, at the distance where the volume's bounding sphere fills the 60° field of view.
render::Camera orbit_pose(const render::Box3& box, int pixels, int pose) {
  const double fov = 60 * std::numbers::pi / 180;
  const double r = 0.5 * box.diagonal();
  const double d = r / std::sin(0.5 * fov);
  const double az = (30.0 + 45.0 * pose) * std::numbers::pi / 180;
  const double el = (pose % 2 ? -25.0 : 25.0) * std::numbers::pi / 180;
  const Vec3 c = box.centre();
  const Vec3 eye = c + d * Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  return render::Pinhole::look_at(pixels, pixels, 0.5 * pixels / std::tan(0.5 * fov), eye, c, Vec3::UnitZ());
}

/// Seed 001's renderer settings: the shapes TF, step 0.2, Phong on, ERT at 0.99 when asked.
struct Method {
  std::string name;
  bool ert, ess;
  render::EmptySpaceScheme scheme = render::EmptySpaceScheme::kOneLevel;
  render::EmptyCellTest test = render::EmptyCellTest::kVoxel;  // the source's index
};
const std::vector<Method>& methods() {
  static const std::vector<Method> m = {
      {"none", false, false},
      {"ert", true, false},
      {"ess", false, true},
      {"ert_ess", true, true},
      {"ess_ml", false, true, render::EmptySpaceScheme::kMultiLevel, render::EmptyCellTest::kRange},
      {"ert_ess_ml", true, true, render::EmptySpaceScheme::kMultiLevel, render::EmptyCellTest::kRange}};
  return m;
}

VolumeRenderSettings settings_for(const Method& m, const render::TransferFunction& tf, double step = 0.2) {
  VolumeRenderSettings s;
  s.model = render::OpticalModel::kTransferFunction;
  s.step_rule = render::StepRule::kFixedStep;
  s.step = step;
  s.tf.table = tf;
  s.ert_transmittance = m.ert ? 0.01 : 0.0;
  s.skip_empty = m.ess;
  s.ess = m.scheme;
  s.ess_test = m.test;
  s.parallel = false;
  return s;
}

struct Timed {
  std::vector<double> wall, cpu;
  VolumeFrame frame;
  double wall_median() const { return median(wall); }
  double cpu_median() const { return median(cpu); }
};

/// Frames of several tracers, interleaved (warm-up rounds, then `repeats` timed rounds of one frame
/// each), so that a change of the machine's load falls on all of them alike.
std::vector<Timed> time_frames_interleaved(const std::vector<const VolumeTracer*>& tracers, const render::Camera& cam,
                                           int warmup, int repeats) {
  std::vector<Timed> t(tracers.size());
  for (int i = 0; i < warmup + repeats; ++i)
    for (std::size_t k = 0; k < tracers.size(); ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = process_cpu_ms();
      t[k].frame = tracers[k]->render(cam);
      const double cpu = process_cpu_ms() - c0, wall = ms_since(t0);
      if (i >= warmup) t[k].wall.push_back(wall), t[k].cpu.push_back(cpu);
    }
  return t;
}

Timed time_frames(const VolumeTracer& tracer, const render::Camera& cam, int warmup, int repeats) {
  return time_frames_interleaved({&tracer}, cam, warmup, repeats).front();
}

/// Per-pixel sample counts as a 16-bit PNG (count / 65535): Fig. 5.1's heat maps are drawn from them.
void write_counts(const fs::path& file, const VolumeFrame& f) {
  ImageF img(f.radiance.width(), f.radiance.height(), 1);
  for (std::size_t i = 0; i < f.sample_counts.size(); ++i)
    img.values()[i] = float(std::min<std::uint32_t>(f.sample_counts[i], 65535)) / 65535.0f;
  write_image(file, img, PixelFormat::kUint16);
}

/// Mean and max |a - b| of two 8-bit images (in levels).
std::pair<double, double> image_diff(const Image8& a, const Image8& b) {
  double sum = 0, worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = std::abs(double(a.values()[i]) - double(b.values()[i]));
    sum += d;
    worst = std::max(worst, d);
  }
  return {sum / double(std::max<std::size_t>(1, a.size())), worst};
}

struct Load {
  render::ClvVolume clv;
  double ms = 0;
};
Load load(const fs::path& file, ClvMemory memory, render::ClvSamples samples = render::ClvSamples::kStored) {
  Load l;
  const auto t0 = std::chrono::steady_clock::now();
  l.clv = render::open_clv(file, memory, samples);
  l.ms = ms_since(t0);
  return l;
}

}  // namespace

// ---- target 13: the generator ------------------------------------------------------------------------

void study_generate(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  CsvTable csv("n,layout,writer,batch,threads,seconds,samples,samples_per_second,file_bytes,expected_bytes");
  const fs::path tmp = dir / "generate.tmp.clv";
  auto run = [&](int n, ClvOrder order, bool naive) {
    const render::ShapesOptions so = shapes_for(n);
    render::ClvWriteOptions w;
    w.order = order;
    w.batch = naive ? 1 : 32768;
    w.parallel = !naive;
    const auto st = render::write_clv_generated(tmp, so.dims, render::ShapesVolume(so), w);
    render::ClvHeader h;
    h.dims = {std::uint32_t(n), std::uint32_t(n), std::uint32_t(n)};
    h.order = order;
    h.block_side = order == ClvOrder::kBlocked ? 16 : 0;
    const std::int64_t samples = h.sample_bytes();
    csv.row("{},{},{},{},{},{:.4f},{},{:.6g},{},{}", n, order == ClvOrder::kBlocked ? "blocked16" : "linear",
            naive ? "naive" : "batched", w.batch, naive ? 1 : int(tbb::info::default_concurrency()), st.seconds,
            samples, double(samples) / st.seconds, std::int64_t(fs::file_size(tmp)), h.file_bytes());
    progress(fmt::format("generate {}³ {} {}: {:.2f} s", n, order == ClvOrder::kBlocked ? "blocked" : "linear",
                         naive ? "naive" : "batched", st.seconds));
    fs::remove(tmp);
  };
  const int naive_n = o.quick ? 96 : 256;
  run(naive_n, ClvOrder::kLinear, true);
  run(naive_n, ClvOrder::kLinear, false);
  for (auto order : {ClvOrder::kLinear, ClvOrder::kBlocked}) run(256, order, false);
  csv.write(dir / "generate.csv");
  // The cached volumes' sizes against the spec's arithmetic, and their statistics.
  CsvTable sizes("n,layout,file_bytes,expected_bytes,occupancy,fraction_visible,shapes,object_size");
  std::vector<int> ns = {256, 800};
  if (!o.quick) ns.push_back(o.large_size);
  for (int n : ns)
    for (auto order : {ClvOrder::kLinear, ClvOrder::kBlocked}) {
      const fs::path f = cached_shapes(n, order);
      const render::ClvHeader h = render::read_clv_header(f);
      std::string occ = "", vis = "";
      if (order == ClvOrder::kLinear) {
        // One pass over the mapped bytes.
        const auto map = MappedFile::open(f, "volume (.clv)");
        map->advise(MappedFile::Advice::kSequential);
        std::vector<std::int64_t> hist(256, 0);
        const std::uint8_t* p = map->data() + render::kClvHeaderBytes;
        for (std::int64_t i = 0; i < h.sample_bytes(); ++i) ++hist[p[i]];
        const auto tf = render::TransferFunction::shapes();
        std::int64_t nz = 0, visible = 0;
        for (int v = 0; v < 256; ++v) {
          if (v) nz += hist[std::size_t(v)];
          if (tf.visible_at(v)) visible += hist[std::size_t(v)];
        }
        occ = fmt::format("{:.6f}", double(nz) / double(h.sample_bytes()));
        vis = fmt::format("{:.6f}", double(visible) / double(h.sample_bytes()));
      }
      const auto so = shapes_for(n);
      sizes.row("{},{},{},{},{},{},{},{}", n, order == ClvOrder::kBlocked ? "blocked16" : "linear",
                std::int64_t(fs::file_size(f)), h.file_bytes(), occ, vis, so.count, so.object_size);
    }
  sizes.write(dir / "sizes.csv");
  record["generate"] = {{"naive", "one write() per sample, one thread (the source's first writer)"},
                        {"batched", "batches of 32768 coordinates, sampled in parallel, written in order"},
                        {"load_average", load_averages()[0]}};
}

// ---- Tables 5.1, 5.2, 5.4 ------------------------------------------------------------------------------

void study_tables(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const int warm_fast = o.quick ? 1 : 2, rep_fast = o.quick ? 3 : 10;
  // One warm-up frame everywhere (pages and caches warm); three timed frames of the brute-force
  // methods too, so that target 9 (RAM against mmap within 5 %) can compare minima: the noise a
  // shared machine adds to one thread's CPU time is one-sided, and a single frame varied by ±8 %.
  const int warm_slow = 1, rep_slow = 3;
  CsvTable csv(
      "table,volume,pixels,method,memory,samples_type,repeats,wall_ms,wall_sd_ms,cpu_ms,cpu_sd_ms,samples,skipped,"
      "terminated,rays,load_average,cpu_min_ms");
  fs::create_directories(dir / "counts");
  auto row = [&](const std::string& table, const std::string& volume, int px, const Method& m, const std::string& mem,
                 const std::string& type, const Timed& t) {
    const auto& st = t.frame.stats;
    csv.row("{},{},{},{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{},{},{},{},{:.2f},{:.3f}", table, volume, px, m.name,
            mem, type, t.wall.size(), t.wall_median(), stddev(t.wall), t.cpu_median(), stddev(t.cpu), st.samples,
            st.skipped, st.terminated, st.rays, load_averages()[0], *std::min_element(t.cpu.begin(), t.cpu.end()));
    progress(fmt::format("Table {} {} {}² {} {} {}: {:.0f} ms ({:.0f} ms CPU), {} samples", table, volume, px, m.name,
                         mem, type, t.wall_median(), t.cpu_median(), st.samples));
  };
  // Table 5.1: the CT-like phantom (68 slices of 256²), samples per image and per pixel (Fig. 5.1).
  {
    render::VolumeGenerateOptions g;
    g.kind = render::VolumeKind::kSkull;
    g.nx = 256, g.ny = 256, g.nz = 68;
    g.shapes.seed = 1;
    const Volume skull = render::generate_volume(g);
    const render::Camera cam = orbit_pose(skull.domain(), 700, 0);
    const auto ranges = render::VolumeRangeIndex::build(skull);
    for (const Method& m : methods()) {
      auto s = settings_for(m, render::TransferFunction::skull());
      s.record_sample_counts = true;
      const VolumeTracer tracer(skull, s, ranges);
      const Timed t = time_frames(tracer, cam, 0, 1);
      row("5.1", "skull 256x256x68", 700, m, "ram", "uint8", t);
      write_counts(dir / "counts" / fmt::format("skull_{}.png", m.name), t.frame);
      if (m.name == "ert_ess")
        write_image(dir / "skull.png", render::tf_output_image(t.frame, render::TfOutput::kPremultiplied));
    }
  }
  // Table 5.2 (and 5.1's counts on the shapes): single thread, RAM and mmap; Table 5.4: float32.
  struct Case {
    int n, px;
    bool floats;
  };
  std::vector<Case> cases;
  if (o.quick)
    cases = {{256, 350, true}, {800, 192, false}};  // quick: the brute-force renders at fewer pixels
  else
    cases = {{800, 700, true}};
  for (const Case& c : cases) {
    const fs::path file = cached_shapes(c.n, ClvOrder::kLinear);
    const std::string vol = fmt::format("shapes {}^3", c.n);
    // RAM and mmap frames of each method interleaved (target 9 compares them), each after at least
    // one warm-up frame: "once pages are warm" — the first frame through a fresh mapping takes a
    // minor fault per page, and the cold first frame is measured apart below.
    Load ram = load(file, ClvMemory::kRam), map = load(file, ClvMemory::kMmap);
    const auto ranges = render::VolumeRangeIndex::build(ram.clv.linear);
    record["tables_index"][vol] = {{"build_ms", ranges->build_ms()}, {"memory_bytes", ranges->memory_bytes()}};
    const render::Camera cam = orbit_pose(ram.clv.linear.domain(), c.px, 0);
    for (const Method& m : methods()) {
      auto s = settings_for(m, render::TransferFunction::shapes());
      s.record_sample_counts = true;
      const VolumeTracer on_ram(ram.clv.linear, s, ranges);
      s.record_sample_counts = false;
      const VolumeTracer on_map(map.clv.linear, s, ranges);
      const bool slow = !m.ess;
      const auto t =
          time_frames_interleaved({&on_ram, &on_map}, cam, slow ? warm_slow : warm_fast, slow ? rep_slow : rep_fast);
      row("5.2", vol, c.px, m, "ram", "uint8", t[0]);
      write_counts(dir / "counts" / fmt::format("shapes{}_{}.png", c.n, m.name), t[0].frame);
      if (m.name == "ert_ess_ml")
        write_image(dir / fmt::format("shapes{}.png", c.n),
                    render::tf_output_image(t[0].frame, render::TfOutput::kPremultiplied));
      row("5.2", vol, c.px, m, "mmap", "uint8", t[1]);
    }
    {
      // Target 9's cold first frame: the file's pages dropped, a fresh map, the index given (so
      // nothing reads the volume before the frame), then the first and a second frame.
      const Method& m = methods().back();
      const auto s = settings_for(m, render::TransferFunction::shapes());
      map.clv = render::ClvVolume{};  // unmapped: its pages may leave the cache
      const bool evicted = evict_from_page_cache(file);
      const render::ClvVolume cold = render::open_clv(file, ClvMemory::kMmap);
      const VolumeTracer tracer(cold.linear, s, ranges);
      const Timed first = time_frames(tracer, cam, 0, 1), second = time_frames(tracer, cam, 0, 1);
      Method cm = m;
      cm.name = evicted ? "ert_ess_ml_cold_first" : "ert_ess_ml_first_not_evicted";
      row("5.2", vol, c.px, cm, "mmap", "uint8", first);
      cm.name = "ert_ess_ml_cold_second";
      row("5.2", vol, c.px, cm, "mmap", "uint8", second);
    }
    if (c.floats) {
      const Load l = load(file, ClvMemory::kRam, render::ClvSamples::kFloat32);
      const auto franges = render::VolumeRangeIndex::build(l.clv.linear);
      for (const Method& m : methods()) {
        const VolumeTracer tracer(l.clv.linear, settings_for(m, render::TransferFunction::shapes()), franges);
        const bool slow = !m.ess;
        const Timed t = time_frames(tracer, cam, slow ? warm_slow : warm_fast, slow ? rep_slow : rep_fast);
        row("5.4", vol, c.px, m, "ram", "float32", t);
      }
    }
  }
  csv.write(dir / "tables.csv");
  record["tables"] = {
      {"tf", "shapes (skull for Table 5.1)"},
      {"step", 0.2},
      {"camera", "orbit pose 0 (azimuth 30, elevation 25, the bounding sphere filling a 60 degree field of view)"},
      {"ess",
       "source: one-level 4^3 cells, per-voxel test (S+1), one step per empty sample; ml: multi-level, range test"},
      {"repeats", {{"slow (no ESS)", rep_slow}, {"fast", rep_fast}, {"warmup_fast", warm_fast}}},
      {"single_thread", true}};
}

// ---- Table 5.3 -------------------------------------------------------------------------------------------

void study_large(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const int n = o.large_size;
  const int px = o.quick ? 350 : 700;
  const fs::path lin = cached_shapes(n, ClvOrder::kLinear), blk = cached_shapes(n, ClvOrder::kBlocked);
  CsvTable csv(
      "row,volume,pixels,method,memory,threads,repeats,wall_ms,wall_sd_ms,cpu_ms,samples,terminated,blocks_visible,"
      "block_tasks,queue_empty_fraction,load_ms,index_ms,load_average");
  auto row = [&](const std::string& name, const Method& m, const std::string& mem, int threads, const Timed& t,
                 double load_ms, double index_ms) {
    const auto& st = t.frame.stats;
    csv.row("{},shapes {}^3,{},{},{},{},{},{:.3f},{:.3f},{:.3f},{},{},{},{},{:.4f},{:.1f},{:.1f},{:.2f}", name, n, px,
            m.name, mem, threads, t.wall.size(), t.wall_median(), stddev(t.wall), t.cpu_median(), st.samples,
            st.terminated, st.blocks_visible, st.block_tasks,
            st.block_tasks ? double(st.queue_empty) / double(st.block_tasks) : 0.0, load_ms, index_ms,
            load_averages()[0]);
    progress(fmt::format("Table 5.3 {}³ {}: {:.0f} ms", n, name, t.wall_median()));
  };
  const int threads = int(tbb::info::default_concurrency());
  {
    // Single thread, RAM: no optimisation, the source's optimisations, multi-level skipping.
    const Load l = load(lin, ClvMemory::kRam);
    evict_from_page_cache(lin);  // the copy is in RAM; give the page cache back
    const render::Camera cam = orbit_pose(l.clv.linear.domain(), px, 0);
    const auto ranges = render::VolumeRangeIndex::build(l.clv.linear);
    for (const Method& m : {methods()[0], methods()[3], methods()[5]}) {
      const VolumeTracer tracer(l.clv.linear, settings_for(m, render::TransferFunction::shapes()), ranges);
      const Timed t = time_frames(tracer, cam, 0, m.ess ? (o.quick ? 3 : 5) : 1);
      row(m.ess ? "single-thread optimised" : "single-thread none", m, "ram", 1, t, l.ms, ranges->build_ms());
    }
    // Image order on the TBB threads (linear, the same index).
    const Load lm = load(lin, ClvMemory::kMmap);
    auto s = settings_for(methods()[5], render::TransferFunction::shapes());
    s.parallel = true;
    const VolumeTracer tracer(lm.clv.linear, s, ranges);
    row("multi-thread image order", methods()[5], "mmap", threads, time_frames(tracer, cam, 1, o.quick ? 3 : 10), lm.ms,
        0);
  }
  {
    // Multi-thread, File: the object-order tiles x blocks renderer on the blocked file, memory-mapped.
    const Load l = load(blk, ClvMemory::kMmap);
    const render::Camera cam = orbit_pose(l.clv.bricked.domain(), px, 0);
    const auto ranges = render::VolumeRangeIndex::build(l.clv.bricked);
    for (const Method& m : {methods()[3], methods()[5]}) {
      auto s = settings_for(m, render::TransferFunction::shapes());
      s.traversal = render::Traversal::kObjectOrder;
      s.parallel = true;
      const VolumeTracer tracer(l.clv.bricked, s, ranges);
      row("multi-thread object order", m, "mmap", threads, time_frames(tracer, cam, 1, o.quick ? 3 : 10), l.ms,
          ranges->build_ms() + tracer.index_build_ms());
    }
  }
  csv.write(dir / "large.csv");
  record["large"] = {{"volume", fmt::format("shapes {}^3 (the spec's {} shapes of size {})", n, shapes_for(n).count,
                                            shapes_for(n).object_size)},
                     {"pixels", px},
                     {"threads", threads},
                     {"note", o.quick ? "quick mode: 800^3 at 350^2 stands in for the 2000^3 frame at 700^2" : ""}};
}

// ---- sweeps: tile size, block side, render threads (target 12) --------------------------------------------

void study_sweeps(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const int n = o.quick ? 256 : 800;
  const int repeats = o.quick ? 2 : 5;
  const int px = o.quick ? 350 : 700;
  const Load l = load(cached_shapes(n, ClvOrder::kLinear), ClvMemory::kRam);
  const render::Camera cam = orbit_pose(l.clv.linear.domain(), px, 0);
  CsvTable csv(
      "sweep,value,tile,block_side,threads,wall_ms,wall_sd_ms,cpu_ms,block_tasks,queue_empty_fraction,busy_fraction,"
      "samples,load_average");
  auto measure = [&](const std::string& sweep, int value, const BrickedVolume& b,
                     const std::shared_ptr<const render::VolumeRangeIndex>& ranges, int tile, int threads) {
    auto s = settings_for(methods()[5], render::TransferFunction::shapes());
    s.traversal = render::Traversal::kObjectOrder;
    s.parallel = true;
    s.tile = tile;
    s.render_threads = threads;
    const VolumeTracer tracer(b, s, ranges);
    const Timed t = time_frames(tracer, cam, 1, repeats);
    const auto& st = t.frame.stats;
    const double busy = st.render_busy_ms / (double(threads) * std::max(1e-9, st.render_ms));
    csv.row("{},{},{},{},{},{:.3f},{:.3f},{:.3f},{},{:.4f},{:.4f},{},{:.2f}", sweep, value, tile, b.side(), threads,
            t.wall_median(), stddev(t.wall), t.cpu_median(), st.block_tasks,
            st.block_tasks ? double(st.queue_empty) / double(st.block_tasks) : 0.0, busy, st.samples,
            load_averages()[0]);
    progress(fmt::format("sweep {} = {}: {:.1f} ms", sweep, value, t.wall_median()));
  };
  const int hw = int(tbb::info::default_concurrency());
  {
    const BrickedVolume b = BrickedVolume::from_volume(l.clv.linear, 16);
    const auto ranges = render::VolumeRangeIndex::build(b);
    for (int tile : {4, 6, 8, 10, 12, 16, 24, 32, 48, 64}) measure("tile", tile, b, ranges, tile, hw);
    for (int threads : {1, 2, 3, 4, 6}) measure("threads", threads, b, ranges, 10, threads);
  }
  for (int side : {8, 12, 16, 24, 32, 48, 64}) {
    const BrickedVolume b = BrickedVolume::from_volume(l.clv.linear, side);
    measure("block_side", side, b, render::VolumeRangeIndex::build(b), 10, hw);
  }
  csv.write(dir / "sweeps.csv");
  record["sweeps"] = {{"volume", fmt::format("shapes {}^3 in RAM, converted to blocks of each side", n)},
                      {"pixels", px},
                      {"renderer", "object order, ERT + ESS (block visibility, multi-level cells)"},
                      {"hardware_threads", hw},
                      {"repeats", repeats}};
}

// ---- the OpenVDB peer ------------------------------------------------------------------------------------

void study_peer(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const int n = o.quick ? 256 : 800;
  const int repeats = o.quick ? 3 : 5;
  const int px = o.quick ? 350 : 700;
  const Load l = load(cached_shapes(n, ClvOrder::kLinear), ClvMemory::kRam);
  const Volume& v = l.clv.linear;
  const render::Camera cam = orbit_pose(v.domain(), px, 0);
  const render::TransferFunction tf = render::TransferFunction::shapes();
  // The same TF as extinction per voxel: σ = -ln(1 - α(value)) (an α of 1 as a large σ).
  const auto t0 = std::chrono::steady_clock::now();
  const render::OpenVdbPeer peer(v, [&](float value) {
    const int r = tf.find(value);
    const double a = r < 0 ? 0.0 : tf.ranges()[std::size_t(r)].alpha;
    return float(a >= 1 ? 50.0 : -std::log1p(-a));
  });
  const double convert_ms = ms_since(t0);
  CsvTable csv(
      "renderer,threads,wall_ms,wall_sd_ms,cpu_ms,samples,mean_abs_alpha_diff,max_abs_alpha_diff,load_average");
  // Ours: ERT + ESS, shading off (the peer cannot shade), image order and object order.
  auto s = settings_for(methods()[5], tf);
  s.tf.shading.enabled = false;
  s.parallel = true;
  const auto ranges = render::VolumeRangeIndex::build(v);
  const VolumeTracer image_order(v, s, ranges);
  const Timed ours = time_frames(image_order, cam, 1, repeats);
  const BrickedVolume b = BrickedVolume::from_volume(v, 16);
  auto sb = s;
  sb.traversal = render::Traversal::kObjectOrder;
  const VolumeTracer object_order(b, sb, render::VolumeRangeIndex::build(b));
  const Timed ours_oo = time_frames(object_order, cam, 1, repeats);
  // OpenVDB: σ per voxel, primary steps of 0.2 voxel, no shadow samples (the shadow step beyond the
  // volume; its shadow ray is still set up per sample), ERT at |T|² < 3·0.01² (A > 0.99).
  render::OpenVdbRenderSettings ps;
  ps.primary_step_voxels = 0.2;
  ps.shadow_step_voxels = 1e9;
  ps.extinction_per_voxel = 1.0;
  ps.albedo = 1.0;
  ps.cutoff = 3e-4;
  std::vector<double> wall, cpu;
  ImageF alpha;
  for (int i = 0; i < 1 + repeats; ++i) {
    const auto w0 = std::chrono::steady_clock::now();
    const double c0 = process_cpu_ms();
    (void)peer.render(cam, ps, &alpha);
    if (i >= 1) wall.push_back(ms_since(w0)), cpu.push_back(process_cpu_ms() - c0);
  }
  auto alpha_diff = [&](const VolumeFrame& f) {
    double sum = 0, worst = 0;
    for (int y = 0; y < alpha.height(); ++y)
      for (int x = 0; x < alpha.width(); ++x) {
        const double d = std::abs((1.0 - double(f.transmittance.at(x, y))) - double(alpha.at(x, y)));
        sum += d;
        worst = std::max(worst, d);
      }
    return std::pair{sum / double(alpha.width() * alpha.height()), worst};
  };
  const int hw = int(tbb::info::default_concurrency());
  const auto d_io = alpha_diff(ours.frame), d_oo = alpha_diff(ours_oo.frame);
  csv.row("meltlab_image_order,{},{:.3f},{:.3f},{:.3f},{},{:.6f},{:.6f},{:.2f}", hw, ours.wall_median(),
          stddev(ours.wall), ours.cpu_median(), ours.frame.stats.samples, d_io.first, d_io.second, load_averages()[0]);
  csv.row("meltlab_object_order,{},{:.3f},{:.3f},{:.3f},{},{:.6f},{:.6f},{:.2f}", hw, ours_oo.wall_median(),
          stddev(ours_oo.wall), ours_oo.cpu_median(), ours_oo.frame.stats.samples, d_oo.first, d_oo.second,
          load_averages()[0]);
  csv.row("openvdb_volume_render,{},{:.3f},{:.3f},{:.3f},,0,0,{:.2f}", hw, median(wall), stddev(wall), median(cpu),
          load_averages()[0]);
  csv.write(dir / "peer.csv");
  ImageF a_ours(alpha.width(), alpha.height(), 1);
  for (int y = 0; y < alpha.height(); ++y)
    for (int x = 0; x < alpha.width(); ++x) a_ours.at(x, y) = 1.0f - ours.frame.transmittance.at(x, y);
  write_image(dir / "peer_alpha_openvdb.png", alpha);
  write_image(dir / "peer_alpha_meltlab.png", a_ours);
  progress(fmt::format("peer {}³: OpenVDB {:.0f} ms, meltlab {:.0f} ms (image order) {:.0f} ms (object order)", n,
                       median(wall), ours.wall_median(), ours_oo.wall_median()));
  record["peer"] = {{"volume", fmt::format("shapes {}^3", n)},
                    {"pixels", px},
                    {"openvdb_active_voxels", peer.active_voxels()},
                    {"openvdb_memory_bytes", peer.memory_bytes()},
                    {"openvdb_convert_ms", convert_ms},
                    {"meltlab_index_bytes", ranges->memory_bytes()},
                    {"meltlab_index_ms", ranges->build_ms()},
                    {"physics",
                     "opacity only (shading off): OpenVDB's grid holds sigma = -ln(1 - alpha) of the TF at "
                     "each voxel (classified, then interpolated); meltlab interpolates, then classifies"}};
}

// ---- Fig. 5.2: step 0.2 against 0.9 -------------------------------------------------------------------------

void study_steps(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const int n = o.quick ? 256 : 800;
  const int px = o.quick ? 350 : 700;
  const Load l = load(cached_shapes(n, ClvOrder::kLinear), ClvMemory::kRam);
  const Volume& v = l.clv.linear;
  const render::Camera cam = orbit_pose(v.domain(), px, 0);
  const auto ranges = render::VolumeRangeIndex::build(v);
  auto render_step = [&](double step, int repeats) {
    auto s = settings_for(methods()[5], render::TransferFunction::shapes(), step);
    s.parallel = true;
    const VolumeTracer tracer(v, s, ranges);
    return time_frames(tracer, cam, repeats > 1 ? 1 : 0, repeats);
  };
  const Timed ref = render_step(0.05, 1);
  const Image8 ref8 = render::tf_output_image(ref.frame, render::TfOutput::kPremultiplied);
  write_image(dir / "step_0.05.png", ref8);
  CsvTable csv("step,wall_ms,samples,mean_abs_diff_levels,max_abs_diff_levels,load_average");
  for (double step : {0.1, 0.2, 0.5, 0.9}) {
    const Timed t = render_step(step, 3);
    const Image8 img = render::tf_output_image(t.frame, render::TfOutput::kPremultiplied);
    write_image(dir / fmt::format("step_{}.png", step), img);
    const auto d = image_diff(img, ref8);
    csv.row("{},{:.3f},{},{:.4f},{:.0f},{:.2f}", step, t.wall_median(), t.frame.stats.samples, d.first, d.second,
            load_averages()[0]);
  }
  csv.write(dir / "steps.csv");
  record["steps"] = {{"volume", fmt::format("shapes {}^3", n)},
                     {"pixels", px},
                     {"reference", "step 0.05 voxel"},
                     {"difference", "8-bit levels of the premultiplied image"}};
}

// ---- multi-level against one-level skipping over the 8 poses ----------------------------------------------

void study_ess(const VolumeBenchOptions& o, const fs::path& dir, json& record) {
  const int n = o.quick ? 256 : 800;
  const int px = o.quick ? 350 : 700;
  const Load l = load(cached_shapes(n, ClvOrder::kLinear), ClvMemory::kRam);
  const Volume& v = l.clv.linear;
  const auto ranges = render::VolumeRangeIndex::build(v);
  CsvTable csv("pose,method,cpu_ms,wall_ms,samples,skipped,terminated,load_average");
  for (int pose = 0; pose < 8; ++pose) {
    const render::Camera cam = orbit_pose(v.domain(), px, pose);
    for (int mi : {2, 3, 4, 5}) {
      const Method& m = methods()[std::size_t(mi)];
      const VolumeTracer tracer(v, settings_for(m, render::TransferFunction::shapes()), ranges);
      const Timed t = time_frames(tracer, cam, 0, o.quick ? 1 : 3);
      csv.row("{},{},{:.3f},{:.3f},{},{},{},{:.2f}", pose, m.name, t.cpu_median(), t.wall_median(),
              t.frame.stats.samples, t.frame.stats.skipped, t.frame.stats.terminated, load_averages()[0]);
    }
    progress(fmt::format("ESS pose {} done", pose));
  }
  csv.write(dir / "ess.csv");
  record["ess"] = {{"volume", fmt::format("shapes {}^3", n)}, {"pixels", px}, {"threads", 1}};
}

}  // namespace meltlab::experiments::clv_bench
