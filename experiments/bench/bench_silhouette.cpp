// Silhouette rendering time: the giraffe mold (10823 triangles, the monograph's count) seen
// from above, filling ~80% of the image height, at 512x384 ... 4096x3072, binary masks and
// 4x4-supersampled coverage, serial and parallel (TBB row bands) — and, in the same run, a peer:
// OpenCV's cv::fillConvexPoly of every projected front-facing triangle (8 fractional bits, like
// our 1/256 snapping) into a cleared mask; for coverage the peer fills a 4x mask and averages
// it with cv::resize(INTER_AREA).
//
// Wall-clock time (UseRealTime) because the parallel renderer works on TBB threads. Run with
//   --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// and read the medians.

#include <meltlab/datasets/molds.h>
#include <meltlab/render/raster/silhouette.h>

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include <array>
#include <cmath>
#include <vector>

namespace {

using namespace meltlab;

constexpr std::array<std::array<int, 2>, 4> kSizes = {{{512, 384}, {1024, 768}, {2048, 1536}, {4096, 3072}}};

const sim::TriMesh<double>& giraffe() {
  static const sim::TriMesh<double> m =
      sim::TriMesh<double>::from_indexed(datasets::mold_mesh(datasets::Mold::kGiraffe));
  return m;
}

// The giraffe is 184 mm tall: 80% of the image height.
render::OrthographicTopDown camera_for(int size_index) {
  const auto [w, h] = kSizes[std::size_t(size_index)];
  return render::OrthographicTopDown::from_pixels_per_mm(w, h, 0.8 * h / 184.0, render::Vec2d(0, 0));
}

void set_labels(benchmark::State& state, int size_index, int k, const char* who) {
  const auto [w, h] = kSizes[std::size_t(size_index)];
  state.SetLabel(std::string(who) + " " + std::to_string(w) + "x" + std::to_string(h) + " k" + std::to_string(k));
  state.counters["triangles"] = double(giraffe().live_triangle_count());
}

// args: size index, supersample k, parallel (0/1)
void BM_Silhouette(benchmark::State& state) {
  const int si = int(state.range(0)), k = int(state.range(1));
  const bool parallel = state.range(2) != 0;
  const auto& mesh = giraffe();
  render::SilhouetteRenderer r(camera_for(si), render::SilhouetteOptions{k, true, parallel});
  cv::Mat out;
  r.render(mesh, out);  // warm the buffers
  for (auto _ : state) {
    r.render(mesh, out);
    benchmark::DoNotOptimize(out.data);
    benchmark::ClobberMemory();
  }
  set_labels(state, si, k, parallel ? "meltlab parallel" : "meltlab serial");
}

// Peer: project, cull, cv::fillConvexPoly per triangle (k = 1) or into a k-times mask then
// cv::resize(INTER_AREA) to coverage (k > 1).
void BM_FillConvexPolyPeer(benchmark::State& state) {
  const int si = int(state.range(0)), k = int(state.range(1));
  const auto& mesh = giraffe();
  const auto cam = camera_for(si);
  constexpr int kShift = 8;
  const double scale = double(1 << kShift);
  cv::Mat big(cam.height * k, cam.width * k, CV_8UC1), cov;
  std::vector<cv::Point> pts(mesh.vertex_slots());
  for (auto _ : state) {
    big.setTo(0);
    const double cu = 0.5 * (cam.width - 1), cv_ = 0.5 * (cam.height - 1);
    for (std::size_t i = 0; i < mesh.vertex_slots(); ++i) {
      const auto& p = mesh.position[i];
      const double u = (p.x() - cam.centre.x()) * cam.pixels_per_unit + cu;
      const double v = -(p.y() - cam.centre.y()) * cam.pixels_per_unit + cv_;
      // Sub-sample grid of the k-times mask: U = k u + (k - 1) / 2.
      pts[i] = cv::Point(int(std::lround((k * u + 0.5 * (k - 1)) * scale)),
                         int(std::lround((k * v + 0.5 * (k - 1)) * scale)));
    }
    for (std::size_t t = 0; t < mesh.triangle_slots(); ++t) {
      if (!mesh.triangle_alive[t]) continue;
      const auto& f = mesh.triangle[t];
      const cv::Point tri[3] = {pts[std::size_t(f[0])], pts[std::size_t(f[1])], pts[std::size_t(f[2])]};
      const std::int64_t area2 = std::int64_t(tri[1].x - tri[0].x) * (tri[2].y - tri[0].y) -
                                 std::int64_t(tri[1].y - tri[0].y) * (tri[2].x - tri[0].x);
      if (area2 >= 0) continue;  // back-facing or degenerate
      cv::fillConvexPoly(big, tri, 3, cv::Scalar(255), cv::LINE_8, kShift);
    }
    if (k > 1) {
      cv::resize(big, cov, cv::Size(cam.width, cam.height), 0, 0, cv::INTER_AREA);
      benchmark::DoNotOptimize(cov.data);
    }
    benchmark::DoNotOptimize(big.data);
    benchmark::ClobberMemory();
  }
  set_labels(state, si, k, "peer cv::fillConvexPoly");
}

void ours_args(benchmark::internal::Benchmark* b) {
  for (int si = 0; si < 4; ++si)
    for (int k : {1, 4})
      for (int par : {0, 1}) b->Args({si, k, par});
}
void peer_args(benchmark::internal::Benchmark* b) {
  for (int si = 0; si < 4; ++si) b->Args({si, 1});
  for (int si = 0; si < 3; ++si) b->Args({si, 4});  // 16384 x 12288 bytes would be 200 MB
}

}  // namespace

BENCHMARK(BM_Silhouette)->Apply(ours_args)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_FillConvexPolyPeer)->Apply(peer_args)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
