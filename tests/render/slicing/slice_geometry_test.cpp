// Seed 003's slice geometry (render/slicing/slice_geometry.h) against the spec's §5.1-5.2 identities:
// random planes (vertices on the plane and on box edges, 3-6 vertices, convex and counter-clockwise,
// area against a stratified Monte-Carlo estimate), the Cavalieri sum, and the polygon route (the
// GPU's rasterised polygons with perspective-correct interpolation) against the per-pixel ray-plane
// route the renderer takes.

#include <meltlab/render/camera.h>
#include <meltlab/render/slicing/slice_geometry.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace meltlab::render {
namespace {

const Box3 kBox{Eigen::Vector3d(-1.0, 0.5, 2.0), Eigen::Vector3d(1.0, 3.5, 3.5)};  // 2 x 3 x 1.5, off the origin

Eigen::Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Vector3d v(g(rng), g(rng), g(rng));
  return v.normalized();
}

// Depth range of the box along unit n.
std::pair<double, double> depth_range(const Eigen::Vector3d& n) {
  double lo = 1e300, hi = -1e300;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d c(i & 1 ? kBox.hi.x() : kBox.lo.x(), i & 2 ? kBox.hi.y() : kBox.lo.y(),
                            i & 4 ? kBox.hi.z() : kBox.lo.z());
    lo = std::min(lo, n.dot(c));
    hi = std::max(hi, n.dot(c));
  }
  return {lo, hi};
}

TEST(SliceGeometry, RandomPlanesGiveConvexCounterClockwisePolygonsOnTheBoxEdges) {
  std::mt19937_64 rng(3);
  const double L = kBox.diagonal();
  const double tol_plane = 1e-6 * L;  // the spec's bound (§5.1)
  const double tol_edge = 1e-9 * L;   // an edge point has two coordinates on bounds: only round-off
  int counts[7] = {0};
  for (int trial = 0; trial < 100000; ++trial) {
    const Eigen::Vector3d n = random_unit(rng);
    const auto [s_lo, s_hi] = depth_range(n);
    const double s = std::uniform_real_distribution<double>(s_lo, s_hi)(rng);
    const auto poly = slice_polygon(kBox, n, -s);
    ASSERT_GE(poly.size(), 3u) << "trial " << trial;
    ASSERT_LE(poly.size(), 6u);
    ++counts[poly.size()];
    for (const auto& x : poly) {
      ASSERT_LT(std::abs(n.dot(x) - s), tol_plane);
      int on_bounds = 0;
      for (int a = 0; a < 3; ++a) {
        ASSERT_GE(x[a], kBox.lo[a] - tol_edge);
        ASSERT_LE(x[a], kBox.hi[a] + tol_edge);
        on_bounds += std::abs(x[a] - kBox.lo[a]) <= tol_edge || std::abs(x[a] - kBox.hi[a]) <= tol_edge;
      }
      ASSERT_GE(on_bounds, 2) << "a vertex off the box's edges";
    }
    // Convex and counter-clockwise about n: every turn is to the left, seen from the tip of n.
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const auto& a = poly[i];
      const auto& b = poly[(i + 1) % poly.size()];
      const auto& c = poly[(i + 2) % poly.size()];
      ASSERT_GT((b - a).cross(c - b).dot(n), 0.0) << "trial " << trial << " vertex " << i;
    }
  }
  // Random planes of a box reach every count (3 at corners, 6 across the middle).
  for (int k = 3; k <= 6; ++k) EXPECT_GT(counts[k], 0) << k << " vertices never seen";
}

TEST(SliceGeometry, AreaMatchesMonteCarlo) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Vector3d n = random_unit(rng);
    const auto [s_lo, s_hi] = depth_range(n);
    const double s = s_lo + (0.1 + 0.8 * U(rng)) * (s_hi - s_lo);
    const auto poly = slice_polygon(kBox, n, -s);
    ASSERT_GE(poly.size(), 3u);
    const double area = polygon_area(poly, n);
    // Stratified (jittered-grid) Monte Carlo over a square of the plane that holds the box's section.
    const Eigen::Vector3d e1 =
        (std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY()).cross(n).normalized();
    const Eigen::Vector3d e2 = n.cross(e1);
    const Eigen::Vector3d centre = kBox.centre() + (s - n.dot(kBox.centre())) * n;
    const double half = 0.5 * kBox.diagonal();
    const int m = 700;
    std::int64_t inside = 0;
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        const double u = -half + 2 * half * (i + U(rng)) / m, v = -half + 2 * half * (j + U(rng)) / m;
        inside += kBox.contains(centre + u * e1 + v * e2);
      }
    const double mc = double(inside) / (double(m) * m) * (4 * half * half);
    // 0.5 %: the spec's bound; a jittered 700² grid's error is ~perimeter x cell / area, below 0.1 % here.
    EXPECT_NEAR(area, mc, 0.005 * area) << "trial " << trial;
  }
}

TEST(SliceGeometry, CavalieriSumConvergesToTheBoxVolume) {
  std::mt19937_64 rng(7);
  const double V = kBox.size().prod();
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Vector3d n = random_unit(rng);
    const Eigen::Vector3d eye = kBox.centre() - 10 * n;
    double first = -1, last = 0;
    for (int refine : {8, 16, 32, 64, 128}) {
      const auto [s_lo, s_hi] = depth_range(n);
      const double dd = (s_hi - s_lo) / refine * 1.0137;  // not commensurate with the extent
      const SliceStack st = slice_stack(kBox, eye, dd);
      ASSERT_NEAR(st.n.dot(n), 1.0, 1e-12);
      double sum = 0;
      for (int k = 0; k < st.count; ++k) {
        const auto poly = slice_polygon(kBox, st.n, -st.depth(k));
        if (poly.size() >= 3) sum += polygon_area(poly, st.n) * dd;
      }
      const double err = std::abs(sum - V) / V;
      // O(Δd): the partial last interval; relative error <= 2 Δd / extent with room.
      EXPECT_LT(err, 2.0 * dd / (s_hi - s_lo)) << "refine " << refine;
      if (first < 0) first = err;
      last = err;
    }
    // The midpoint planes make it better than O(Δd) on average, though not monotone step by step.
    EXPECT_LT(last, first / 4) << "trial " << trial;
  }
}

TEST(SliceGeometry, ConservativeRangeOnlyAddsEmptyPlanes) {
  const Eigen::Vector3d eye(7, -5, 9);
  const SliceStack tight = slice_stack(kBox, eye, 0.05);
  const SliceStack wide = slice_stack(kBox, eye, 0.05, SliceRange::kConservative);
  EXPECT_GE(wide.count, tight.count);
  double tight_area = 0, wide_area = 0;
  for (int k = 0; k < tight.count; ++k) {
    const auto p = slice_polygon(kBox, tight.n, -tight.depth(k));
    if (p.size() >= 3) tight_area += polygon_area(p, tight.n);
  }
  for (int k = 0; k < wide.count; ++k) {
    const auto p = slice_polygon(kBox, wide.n, -wide.depth(k));
    if (p.size() >= 3) wide_area += polygon_area(p, wide.n);
  }
  // Different plane offsets, same box: both sums approximate V / Δd within the O(Δd) edge term.
  EXPECT_NEAR(tight_area * 0.05, wide_area * 0.05, 0.02 * kBox.size().prod());
}

// The polygon route: rasterise each slice polygon (triangle fan, pixel centres, perspective-correct
// interpolation of the 3-D position as the GPU interpolates texture coordinates) and compare with
// the per-pixel ray-plane route of ray_slices: the same pixels (away from polygon edges, where
// coverage is a matter of round-off) and the same points.
TEST(SliceGeometry, PolygonRasterisationAndRayPlaneSamplingGiveTheSameSamples) {
  const int W = 96, H = 72;
  const double fov = 30.0 * M_PI / 180.0;
  const double fy = 0.5 * H / std::tan(0.5 * fov);
  const Eigen::Vector3d eye = kBox.centre() + Eigen::Vector3d(3.0, -6.5, 2.5);
  const Camera cam = Pinhole::look_at(W, H, fy, eye, kBox.centre(), Eigen::Vector3d(0, 0, 1));
  const RayGenerator rays(cam);
  const SliceStack st = slice_stack(kBox, eye, 0.11);
  std::vector<RaySlices> per_pixel(std::size_t(W) * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const CameraRay r = rays.generate_ray(x, y);
      per_pixel[std::size_t(y) * W + x] = ray_slices(st, kBox, r.origin, r.direction);
    }
  std::int64_t compared = 0, near_edge = 0;
  double worst = 0;
  for (int k = 0; k < st.count; ++k) {
    const auto poly = slice_polygon(kBox, st.n, -st.depth(k));
    if (poly.size() < 3) continue;
    std::vector<Projection> pr;
    for (const auto& v : poly) pr.push_back(rays.project(v));
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const Eigen::Vector2d q(x, y);
        // Coverage and perspective-correct position from the fan triangle holding the pixel centre.
        bool covered = false, edge = false;
        Eigen::Vector3d p_poly = Eigen::Vector3d::Zero();
        for (std::size_t t = 1; t + 1 < poly.size(); ++t) {
          const Eigen::Vector2d a = pr[0].pixel, b = pr[t].pixel, c = pr[t + 1].pixel;
          auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) { return u.x() * v.y() - u.y() * v.x(); };
          const double area = cross(b - a, c - a);
          const double l0 = cross(b - q, c - q) / area, l1 = cross(c - q, a - q) / area,
                       l2 = cross(a - q, b - q) / area;
          const double m = std::min({l0, l1, l2});
          if (std::abs(m) < 1e-6) edge = true;
          if (m >= 0 && !covered) {
            covered = true;
            const double w0 = l0 / pr[0].depth, w1 = l1 / pr[t].depth, w2 = l2 / pr[t + 1].depth;
            p_poly = (w0 * poly[0] + w1 * poly[t] + w2 * poly[t + 1]) / (w0 + w1 + w2);
          }
        }
        const RaySlices& rs = per_pixel[std::size_t(y) * W + x];
        const bool ray_hit = !rs.empty() && k >= rs.k_first && k <= rs.k_last;
        if (covered != ray_hit) {
          // Allowed only where the pixel centre lies on a fan triangle's edge (round-off decides).
          ASSERT_TRUE(edge) << "slice " << k << " pixel " << x << "," << y << " polygon " << covered << " ray "
                            << ray_hit;
          ++near_edge;
          continue;
        }
        if (!covered) continue;
        const CameraRay r = rays.generate_ray(x, y);
        const Eigen::Vector3d p_ray = r.origin + rs.t(st, k) * r.direction;
        worst = std::max(worst, (p_ray - p_poly).norm());
        ++compared;
      }
  }
  EXPECT_GT(compared, 10000);
  EXPECT_LT(near_edge, compared / 1000 + 1);
  // Double round-off over distances of ~10 scene units (the eye to the box).
  EXPECT_LT(worst, 1e-9 * kBox.diagonal()) << "worst distance between the two routes' sample points";
}

}  // namespace
}  // namespace meltlab::render
