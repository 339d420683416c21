// Silhouette rasterizer (raster/silhouette.h): exact pixel counts, fill rule, coverage, culling,
// parallel determinism, clipping and lens distortion.

#include <meltlab/datasets/molds.h>
#include <meltlab/datasets/procedural.h>
#include <meltlab/render/raster/silhouette.h>
#include <meltlab/core/error.h>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <numbers>
#include <random>

namespace meltlab::render {
namespace {

using sim::IndexedMesh;
using sim::TriMesh;

TriMesh<double> tri(const IndexedMesh& m) { return TriMesh<double>::from_indexed(m); }

// Axis-aligned box [x0, x1] x [y0, y1] x [0, h] (closed, outward), from the unit cube.
IndexedMesh box(double x0, double x1, double y0, double y1, double h) {
  IndexedMesh m = datasets::cube_triangles(1.0);
  for (auto& p : m.V) {
    p.x() = p.x() < 0 ? x0 : x1;
    p.y() = p.y() < 0 ? y0 : y1;
    p.z() = p.z() < 0 ? 0.0 : h;
  }
  return m;
}

const IndexedMesh& giraffe() {
  static const IndexedMesh m = datasets::mold_mesh(datasets::Mold::kGiraffe);
  return m;
}

// Giraffe (153 x 184 mm) at 6 px/mm fits 2048 x 1536 with margin.
OrthographicTopDown giraffe_camera() { return OrthographicTopDown::from_pixels_per_mm(2048, 1536, 6.0, Vec2d(0, 0)); }

int count(const cv::Mat& m) { return cv::countNonZero(m); }
int mismatch(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat x;
  cv::bitwise_xor(a, b, x);
  return cv::countNonZero(x);
}
bool binary_values(const cv::Mat& m) {
  for (int j = 0; j < m.rows; ++j)
    for (int i = 0; i < m.cols; ++i)
      if (m.at<std::uint8_t>(j, i) != 0 && m.at<std::uint8_t>(j, i) != 255) return false;
  return true;
}

// Convex hull (monotone chain) of 2-D points; counter-clockwise in (u, v).
std::vector<Vec2d> hull(std::vector<Vec2d> p) {
  std::sort(p.begin(), p.end(),
            [](const Vec2d& a, const Vec2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  auto cross = [](const Vec2d& o, const Vec2d& a, const Vec2d& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  std::vector<Vec2d> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);
  return h;
}
double area(const std::vector<Vec2d>& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2d& p = poly[i];
    const Vec2d& q = poly[(i + 1) % poly.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * std::abs(a);
}
double perimeter(const std::vector<Vec2d>& poly) {
  double s = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) s += (poly[(i + 1) % poly.size()] - poly[i]).norm();
  return s;
}
std::vector<Vec2d> projected_hull(const IndexedMesh& m, const Camera& c) {
  const RayGenerator rays(c);
  std::vector<Vec2d> pts;
  for (const auto& v : m.V) pts.push_back(rays.project(v).pixel);
  return hull(pts);
}

// ---- exact pixel counts ----------------------------------------------------------------

TEST(Silhouette, BoxFromAboveCoversExactlyThePixelCentresInsideItsRectangle) {
  // 1 px/mm, 640 x 480: u = 1000 x + 319.5, v = -1000 y + 239.5.
  const Camera cam = OrthographicTopDown::from_pixels_per_mm(640, 480, 1.0, Vec2d(0, 0));
  const double x0 = -0.1234, x1 = 0.0567, y0 = -0.0711, y1 = 0.1022;
  const cv::Mat m = silhouette_mask(box(x0, x1, y0, y1, 0.03), cam);
  ASSERT_EQ(m.type(), CV_8UC1);
  EXPECT_TRUE(binary_values(m));
  // By hand: u from 196.1 to 376.2 -> columns 197..376 (180); v from 137.3 (top, y1) to 310.6
  // (bottom, y0) -> rows 138..310 (173). No edge passes through a pixel centre.
  cv::Mat expected = cv::Mat::zeros(480, 640, CV_8UC1);
  expected(cv::Rect(197, 138, 180, 173)).setTo(255);
  EXPECT_EQ(count(m), 180 * 173);
  EXPECT_EQ(mismatch(m, expected), 0);
}

TEST(Silhouette, EdgesThroughPixelCentresFollowTheTopLeftRule) {
  // 1024 px per unit and dyadic coordinates: every edge lies exactly on pixel centres.
  // u = 1024 x + 319.5 and v = -1024 y + 239.5 are integers for x, y = (n + 0.5) / 1024.
  OrthographicTopDown cam;
  cam.width = 640;
  cam.height = 480;
  cam.pixels_per_unit = 1024.0;
  auto X = [](int u) { return (u - 319.5) / 1024.0; };
  auto Y = [](int v) { return (239.5 - v) / 1024.0; };
  // Columns 100..300 and rows 50..200 lie on the edges: left/top included, right/bottom not.
  const cv::Mat m = silhouette_mask(box(X(100), X(300), Y(200), Y(50), 0.01), Camera(cam));
  cv::Mat expected = cv::Mat::zeros(480, 640, CV_8UC1);
  expected(cv::Rect(100, 50, 200, 150)).setTo(255);
  EXPECT_EQ(count(m), 200 * 150);
  EXPECT_EQ(mismatch(m, expected), 0);
}

TEST(Silhouette, SpherePixelCountApproachesPiRSquared) {
  // Geodesic sphere f = 48 (46080 triangles). Two sources of error:
  //  - pixels: |count - area| <= 2 P + 8 for a convex region of perimeter P (only pixels
  //    whose square meets the boundary can disagree, at most 2 per unit of boundary length
  //    plus the corners), i.e. a relative bound 4 / r that shrinks with resolution;
  //  - the mesh: its outline is inscribed in the circle; edges subtend <= 1.6 degrees at
  //    f = 48, so the area deficit is below 2 (1 - cos 1.6°) = 8e-4 of pi r^2.
  const IndexedMesh sphere = datasets::geodesic_sphere(48, 1.0);
  const TriMesh<double> m = tri(sphere);
  double previous_bound = 1e9;
  for (double r : {20.0, 80.0, 320.0, 700.0}) {
    OrthographicTopDown cam;
    cam.width = cam.height = int(2 * r) + 16;
    cam.pixels_per_unit = r;
    const cv::Mat mask = silhouette_mask(m, Camera(cam));
    const double exact = std::numbers::pi * r * r;
    const double rel = std::abs(count(mask) - exact) / exact;
    const double bound = (2 * 2 * std::numbers::pi * r + 8) / exact + 8e-4;
    EXPECT_LT(rel, bound) << "r = " << r;
    EXPECT_LT(bound, previous_bound);
    previous_bound = bound;
    // Against the exact projected outline (the hull of the projected vertices) only the
    // pixel term remains.
    const auto h = projected_hull(sphere, Camera(cam));
    EXPECT_LE(std::abs(count(mask) - area(h)), 2 * perimeter(h) + 8) << "r = " << r;
  }
}

TEST(Silhouette, SupersampledCoverageConvergesToTheExactArea) {
  // k x k samples: |sum - area| <= (2 P k + 8) / k^2 by the pixel argument on the k-times grid.
  const IndexedMesh sphere = datasets::geodesic_sphere(32, 1.0);
  OrthographicTopDown cam;
  cam.width = 90;
  cam.height = 80;
  cam.pixels_per_unit = 30.3;
  const auto h = projected_hull(sphere, Camera(cam));
  const double A = area(h), P = perimeter(h);
  double last_err = 1e9;
  for (int k : {1, 2, 4, 8, 16}) {
    const cv::Mat cov = silhouette_coverage(tri(sphere), Camera(cam), SilhouetteOptions{k, true, true});
    ASSERT_EQ(cov.type(), CV_32FC1);
    double mn = 0, mx = 0;
    cv::minMaxLoc(cov, &mn, &mx);
    EXPECT_GE(mn, 0.0);
    EXPECT_LE(mx, 1.0);
    const double err = std::abs(cv::sum(cov)[0] - A);
    EXPECT_LE(err, (2 * P * k + 8) / (k * k)) << "k = " << k;
    last_err = err;
  }
  // At k = 16 the error is a small fraction of a pixel per boundary pixel.
  EXPECT_LT(last_err / P, 0.05);

  // A box has an exactly computable sample count: with k = 4 the samples of columns lie at
  // u = i - 0.375, -0.125, 0.125, 0.375.
  const Camera bc = OrthographicTopDown::from_pixels_per_mm(64, 48, 1.0, Vec2d(0, 0));  // u = 1000x + 31.5
  const cv::Mat cov =
      silhouette_coverage(tri(box(-0.0101, 0.0123, -0.0052, 0.0071, 0.01)), bc, SilhouetteOptions{4, true, true});
  auto samples = [](double a, double b) {  // sample positions s/4 - 0.375 (s integer) in [a, b)
    return int(std::ceil((b + 0.375) * 4) - std::ceil((a + 0.375) * 4));
  };
  const int nx = samples(-10.1 + 31.5, 12.3 + 31.5), ny = samples(-7.1 + 23.5, 5.2 + 23.5);
  EXPECT_DOUBLE_EQ(cv::sum(cov)[0], nx * ny / 16.0);
}

// ---- fill rule: shared edges ------------------------------------------------------------

// Reference: the top-left rule for a convex polygon with vertices on the 1/256 grid, in exact
// integer arithmetic: pixel centre p is inside iff p + (eps, eps^2) is in the interior.
bool inside_top_left(const std::vector<Vec2d>& poly_ccw_uv_down, int i, int j) {
  // Polygon orientation: signed area in (u, v) negative (counter-clockwise seen from above).
  const std::size_t n = poly_ccw_uv_down.size();
  for (std::size_t e = 0; e < n; ++e) {
    const Vec2d& a = poly_ccw_uv_down[e];
    const Vec2d& b = poly_ccw_uv_down[(e + 1) % n];
    const std::int64_t ax = std::llround(a.x() * 256), ay = std::llround(a.y() * 256);
    const std::int64_t bx = std::llround(b.x() * 256), by = std::llround(b.y() * 256);
    const std::int64_t px = std::int64_t(i) * 256, py = std::int64_t(j) * 256;
    // Interior normal of a clockwise-in-(u, v) loop: n = (dy, -dx) rotated... compute directly:
    // E > 0 inside for the negative-area orientation.
    const std::int64_t dx = bx - ax, dy = by - ay;
    const std::int64_t E = dy * (px - ax) - dx * (py - ay);  // = -(cross(d, p - a))
    const std::int64_t nx = dy, ny = -dx;                    // gradient of E: points inside
    if (E < 0) return false;
    if (E == 0 && !(nx > 0 || (nx == 0 && ny > 0))) return false;
  }
  return true;
}

TEST(Silhouette, TrianglesSharingAnEdgeNeitherOverlapNorLeaveGaps) {
  constexpr int W = 64, H = 48;
  OrthographicTopDown cam;  // u = x + 31.5, v = 23.5 - y
  cam.width = W;
  cam.height = H;
  cam.pixels_per_unit = 1.0;
  std::mt19937 rng(11);
  // Vertices on a coarse grid (halves: often exactly on pixel centres, edges often horizontal
  // or vertical) or on the fine 1/256 grid.
  for (int trial = 0; trial < 400; ++trial) {
    const bool coarse = trial % 2 == 0;
    std::uniform_int_distribution<int> du(coarse ? -2 : -512, coarse ? 2 * (W + 1) : 256 * (W + 2));
    std::uniform_int_distribution<int> dv(coarse ? -2 : -512, coarse ? 2 * (H + 1) : 256 * (H + 2));
    const double scale = coarse ? 0.5 : 1.0 / 256;
    std::vector<Vec2d> pts;
    for (int i = 0; i < 4; ++i) pts.emplace_back(du(rng) * scale, dv(rng) * scale);
    std::vector<Vec2d> q = hull(pts);  // counter-clockwise in (u, v) = clockwise seen from above
    if (q.size() != 4 || area(q) < 1.0) continue;
    std::reverse(q.begin(), q.end());  // counter-clockwise seen from above
    TriMesh<double> m;
    for (const Vec2d& p : q) m.add_vertex(sim::Vec3<double>(p.x() - 31.5, 23.5 - p.y(), 0.0));
    auto render_tris = [&](std::vector<sim::Triangle> ts) {
      TriMesh<double> mm = m;
      for (const auto& t : ts) mm.add_triangle(t[0], t[1], t[2]);
      return silhouette_mask(mm, Camera(cam));
    };
    const cv::Mat t1 = render_tris({{0, 1, 2}}), t2 = render_tris({{0, 2, 3}});
    const cv::Mat both = render_tris({{0, 1, 2}, {0, 2, 3}});
    const cv::Mat other_diagonal = render_tris({{0, 1, 3}, {1, 2, 3}});
    cv::Mat overlap;
    cv::bitwise_and(t1, t2, overlap);
    EXPECT_EQ(count(overlap), 0) << "trial " << trial;
    EXPECT_EQ(count(t1) + count(t2), count(both)) << "trial " << trial;
    EXPECT_EQ(mismatch(both, other_diagonal), 0) << "trial " << trial;
    cv::Mat quad = cv::Mat::zeros(H, W, CV_8UC1);
    for (int j = 0; j < H; ++j)
      for (int i = 0; i < W; ++i)
        if (inside_top_left(q, i, j)) quad.at<std::uint8_t>(j, i) = 255;
    EXPECT_EQ(mismatch(both, quad), 0) << "trial " << trial;
  }
}

TEST(Silhouette, FanAroundAPixelCentreCountsEveryPixelOnce) {
  // A regular 12-gon fanned around a vertex exactly on a pixel centre: the sum of the
  // triangles' own masks equals the union (no pixel twice), and the union is the polygon.
  OrthographicTopDown cam;
  cam.width = 64;
  cam.height = 48;
  cam.pixels_per_unit = 1.0;
  TriMesh<double> m;
  m.add_vertex({0.5, 0.5, 0});  // u = 32, v = 23
  for (int i = 0; i < 12; ++i) {
    const double a = 2 * std::numbers::pi * i / 12;
    m.add_vertex({0.5 + std::round(256 * 14 * std::cos(a)) / 256, 0.5 + std::round(256 * 14 * std::sin(a)) / 256, 0});
  }
  int sum = 0;
  TriMesh<double> all = m;
  for (int i = 0; i < 12; ++i) {
    TriMesh<double> one = m;
    one.add_triangle(0, 1 + i, 1 + (i + 1) % 12);
    all.add_triangle(0, 1 + i, 1 + (i + 1) % 12);
    sum += count(silhouette_mask(one, Camera(cam)));
  }
  const cv::Mat u = silhouette_mask(all, Camera(cam));
  EXPECT_EQ(sum, count(u));
  std::vector<Vec2d> poly;  // clockwise in (u, v) as required by inside_top_left
  const RayGenerator rays(cam);
  for (int i = 0; i < 12; ++i) poly.push_back(rays.project(all.position[std::size_t(1 + i)]).pixel);
  int ref = 0;
  for (int j = 0; j < 48; ++j)
    for (int i = 0; i < 64; ++i) ref += inside_top_left(poly, i, j);
  EXPECT_EQ(count(u), ref);
  EXPECT_EQ(u.at<std::uint8_t>(23, 32), 255);  // the shared centre vertex belongs to exactly one triangle
}

// ---- culling, dead triangles, determinism ------------------------------------------------

TEST(Silhouette, CullingDoesNotChangeTheMaskOfAClosedMesh) {
  // The result depends only on the covered region (exact fill rule), and front and back
  // faces of a closed mesh cover the same region: the masks are identical.
  const std::vector<IndexedMesh> meshes = {datasets::geodesic_sphere(20, 0.05), datasets::torus(0.05, 0.02, 48, 24),
                                           giraffe()};
  const std::vector<Camera> cams = {
      OrthographicTopDown::from_pixels_per_mm(1024, 768, 3.0, Vec2d(0.001, -0.002)),
      Pinhole::look_at(1024, 768, 1500.0, Vec3d(0.15, -0.25, 0.3), Vec3d(0, 0, 0.01)),
  };
  for (const auto& mesh : meshes) {
    for (const auto& cam : cams) {
      const cv::Mat on = silhouette_mask(mesh, cam, SilhouetteOptions{1, true, true});
      const cv::Mat off = silhouette_mask(mesh, cam, SilhouetteOptions{1, false, true});
      EXPECT_GT(count(on), 1000);
      EXPECT_EQ(mismatch(on, off), 0);
    }
  }
}

TEST(Silhouette, SerialAndParallelAreIdentical) {
  const TriMesh<double> m = tri(giraffe());
  Pinhole distorted = Pinhole::look_at(1024, 768, 1100.0, Vec3d(0.05, -0.1, 0.35), Vec3d(0, 0, 0.01));
  distorted.distortion = {-0.2, 0.05, 0.001, -0.001, 0.0};
  for (const Camera& cam : {Camera(giraffe_camera()), Camera(distorted)}) {
    for (int k : {1, 4}) {
      SilhouetteRenderer serial(cam, SilhouetteOptions{k, true, false});
      SilhouetteRenderer parallel(cam, SilhouetteOptions{k, true, true});
      cv::Mat a, b;
      serial.render(m, a);
      parallel.render(m, b);
      ASSERT_EQ(a.type(), b.type());
      EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "k = " << k;
      EXPECT_GT(cv::countNonZero(a), 1000);
      // Rendering again into the same buffers gives the same image.
      parallel.render(m, b);
      EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "k = " << k;
    }
  }
}

TEST(Silhouette, DeadTrianglesAreSkipped) {
  TriMesh<double> m = tri(datasets::geodesic_sphere(12, 0.05));
  for (std::size_t t = 0; t < m.triangle_slots(); t += 3) m.triangle_alive[t] = 0;
  const Camera cam = OrthographicTopDown::from_pixels_per_mm(400, 300, 2.0, Vec2d(0, 0));
  const cv::Mat with_dead = silhouette_mask(m, cam);
  const cv::Mat compact = silhouette_mask(m.to_indexed(), cam);
  EXPECT_EQ(mismatch(with_dead, compact), 0);
  const cv::Mat full = silhouette_mask(datasets::geodesic_sphere(12, 0.05), cam);
  EXPECT_LT(count(with_dead), count(full));  // holes: the dead triangles are not drawn
}

TEST(Silhouette, BadInputIsAnInputError) {
  TriMesh<double> m = tri(datasets::cube_triangles(0.01));
  m.triangle[0][1] = 99;
  const Camera cam = OrthographicTopDown::from_pixels_per_mm(64, 48, 1.0, Vec2d(0, 0));
  EXPECT_THROW(silhouette_mask(m, cam), InputError);
  EXPECT_THROW(SilhouetteRenderer(cam, SilhouetteOptions{0, true, true}), InputError);
  Pinhole p;
  p.fx = -1;
  EXPECT_THROW(SilhouetteRenderer(Camera(p), SilhouetteOptions{}), InputError);
}

// ---- pinhole: clipping, distortion, far-away limit ----------------------------------------

TEST(Silhouette, GroundReachingBehindThePinholeIsClippedNotGarbage) {
  // A 200 m ground square under a camera 1 m up looking 1:10 down towards +y: half of the
  // square is behind the camera. Visible: everything below the image of the far edge
  // (y = 100 m), nothing above it, whole rows.
  IndexedMesh g;
  g.V = {{-100, -100, 0}, {100, -100, 0}, {100, 100, 0}, {-100, 100, 0}};
  g.F = {{0, 1, 2}, {0, 2, 3}};
  const Pinhole p = Pinhole::look_at(640, 480, 500.0, Vec3d(0, 0, 1), Vec3d(0, 10, 0));
  const cv::Mat m = silhouette_mask(g, Camera(p));
  const double v_far = RayGenerator(p).project(Vec3d(0, 100, 0)).pixel.y();  // about 239.5 - 500 * (0.1 - 0.01)
  ASSERT_GT(v_far, 150);
  ASSERT_LT(v_far, 239.5);
  for (int j = 0; j < 480; ++j) {
    const int n = cv::countNonZero(m.row(j));
    if (j < v_far - 1) {
      EXPECT_EQ(n, 0) << "row " << j;
    }
    if (j > v_far + 1) {
      EXPECT_EQ(n, 640) << "row " << j;
    }
  }
  // The same square seen from below is back-facing: nothing drawn with culling.
  const Pinhole below = Pinhole::look_at(640, 480, 500.0, Vec3d(0, 0, -1), Vec3d(0, 10, 0));
  EXPECT_EQ(count(silhouette_mask(g, Camera(below))), 0);
  EXPECT_GT(count(silhouette_mask(g, Camera(below), SilhouetteOptions{1, false, true})), 10000);
}

TEST(Silhouette, DistortionPathWithNegligibleDistortionEqualsTheUndistortedMask) {
  const TriMesh<double> m = tri(giraffe());
  Pinhole p = Pinhole::look_at(1024, 768, 1200.0, Vec3d(0.02, -0.05, 0.4), Vec3d(0, 0, 0.01));
  const cv::Mat ideal = silhouette_mask(m, Camera(p));
  EXPECT_FALSE(p.distorted());
  // k1 = 1e-13 moves no point by more than ~1e-10 px: the remap path (ideal canvas + maps)
  // must land every output pixel exactly on its own ideal pixel.
  p.distortion = {1e-13, 0, 0, 0, 0};
  ASSERT_TRUE(p.distorted());
  const cv::Mat through_maps = silhouette_mask(m, Camera(p));
  EXPECT_GT(count(ideal), 10000);
  EXPECT_EQ(mismatch(ideal, through_maps), 0);
}

TEST(Silhouette, DistortedMaskMatchesPerPixelUndistortionToHalfAPixel) {
  // Strong barrel distortion; reference: undistort each output pixel centre with OpenCV and
  // test it against the exact (convex) ideal outline of a sphere. The renderer looks up the
  // nearest ideal pixel, so a pixel may only disagree if its ideal position is within
  // half a pixel diagonal (0.71 px) of the outline (+ 0.01 px for snapping and float maps).
  const IndexedMesh sphere = datasets::geodesic_sphere(24, 0.05);
  Pinhole p = Pinhole::look_at(320, 240, 300.0, Vec3d(0.08, 0.02, 0.2), Vec3d(0.04, -0.03, 0.0));
  Pinhole ideal_cam = p;
  p.distortion = {-0.3, 0.08, 0.002, -0.001, 0.0};
  const cv::Mat m = silhouette_mask(sphere, Camera(p));
  const RayGenerator ideal_rays(ideal_cam);
  std::vector<Vec2d> ideal_pts;
  for (const auto& v : sphere.V) ideal_pts.push_back(ideal_rays.project(v).pixel);
  const std::vector<Vec2d> h = hull(ideal_pts);
  std::vector<cv::Point2f> contour;
  for (const auto& q : h) contour.emplace_back(float(q.x()), float(q.y()));
  std::vector<cv::Point2f> pix, und;
  for (int j = 0; j < 240; ++j)
    for (int i = 0; i < 320; ++i) pix.emplace_back(float(i), float(j));
  const cv::Mat K = (cv::Mat_<double>(3, 3) << p.fx, 0, p.cx, 0, p.fy, p.cy, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(1, 5) << p.distortion[0], p.distortion[1], p.distortion[2], p.distortion[3], 0.0);
  cv::undistortPoints(pix, und, K, D, cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  int inside = 0, bad = 0;
  for (std::size_t n = 0; n < pix.size(); ++n) {
    const double d = cv::pointPolygonTest(contour, und[n], true);  // > 0 inside
    const bool ref = d > 0;
    const bool got = m.at<std::uint8_t>(int(pix[n].y), int(pix[n].x)) != 0;
    inside += ref;
    if (ref != got && std::abs(d) > 0.72) ++bad;
  }
  EXPECT_GT(inside, 3000);
  EXPECT_EQ(bad, 0);
}

TEST(Silhouette, FarPinholeLookingDownApproachesTheOrthographicMask) {
  // Camera 1 km above the giraffe block with f chosen so the top face (z = t) has the
  // orthographic scale: the perspective scale differs by t / D ~ 3e-5 across the block
  // (< 0.03 px at the image edge), so masks differ only where a boundary passes within
  // ~0.03 px (+ rounding) of a pixel centre: P = |A xor B| / |A or B| < 1e-3.
  const datasets::MoldBlock b = datasets::mold_block(datasets::Mold::kGiraffe);
  const OrthographicTopDown ortho = giraffe_camera();
  const double D = 1000.0;
  const Pinhole far =
      Pinhole::look_at(2048, 1536, ortho.pixels_per_unit * (D - b.thickness_m), Vec3d(0, 0, D), Vec3d(0, 0, 0));
  const cv::Mat a = silhouette_mask(b.mesh, Camera(ortho));
  const cv::Mat c = silhouette_mask(b.mesh, Camera(far));
  cv::Mat uni;
  cv::bitwise_or(a, c, uni);
  const double P = double(mismatch(a, c)) / count(uni);
  EXPECT_GT(count(uni), 100000);
  EXPECT_LT(P, 1e-3);
  // The orthographic area matches the block's outline area (6 px/mm = 36 px per mm^2) up to the
  // pixel term (2 x perimeter ~ 2 x 1 m x 6000 px/m / area ~ 4%).
  EXPECT_NEAR(count(a) / (b.outline_area_m2 * 36e6), 1.0, 0.04);
}

TEST(Silhouette, ACroppedCameraRendersTheFullCamerasSubWindow) {
  // The fit renders photo windows through crop(): the same pixels as the full render's window
  // (coverage exactly, binary and supersampled) for both camera kinds. Differences could only
  // come from a vertex landing within round-off (~1e-13 px) of a sub-sample snapping boundary.
  const IndexedMesh sphere = datasets::geodesic_sphere(16, 0.05);
  OrthographicTopDown ortho;
  ortho.width = 320;
  ortho.height = 240;
  ortho.pixels_per_unit = 1900.0;
  ortho.centre = Vec2d(0.004, -0.003);
  const Camera pinhole = Pinhole::look_at(320, 240, 600.0, Vec3d(0.05, -0.08, 0.3), Vec3d(0.01, 0.0, 0.0));
  const PixelWindow window{180, 30, 121, 88};  // across the sphere's right side
  const cv::Rect rect(window.x, window.y, window.width, window.height);
  for (const Camera& full : {Camera(ortho), pinhole}) {
    for (int k : {1, 4}) {
      SilhouetteRenderer whole(full, SilhouetteOptions{k, true});
      SilhouetteRenderer part(crop(full, window), SilhouetteOptions{k, true});
      cv::Mat a, b;
      whole.render(sphere, a);
      part.render(sphere, b);
      ASSERT_EQ(b.size(), rect.size());
      cv::Mat diff;
      cv::absdiff(a(rect), b, diff);
      EXPECT_EQ(cv::countNonZero(diff.reshape(1)), 0) << full.index() << " k = " << k;
      // The window holds part of the outline (not all empty or all covered).
      double lo = 0, hi = 0;
      cv::minMaxLoc(b, &lo, &hi);
      EXPECT_LT(lo, hi) << full.index() << " k = " << k;
    }
  }
}

TEST(Silhouette, IndexedAndTriMeshAndFloatAgree) {
  const IndexedMesh s = datasets::geodesic_sphere(16, 0.05);
  const Camera cam = Pinhole::look_at(640, 480, 800.0, Vec3d(0.1, 0.1, 0.3), Vec3d(0, 0, 0));
  const cv::Mat a = silhouette_mask(s, cam);
  const cv::Mat b = silhouette_mask(tri(s), cam);
  EXPECT_EQ(mismatch(a, b), 0);
  // float positions move vertices by ~1e-8 m ~ 3e-5 px: only pixel centres within that of an
  // edge can change (a handful at most).
  const cv::Mat f = silhouette_mask(tri(s).cast<float>(), cam);
  EXPECT_LE(mismatch(a, f), 5);
}

}  // namespace
}  // namespace meltlab::render
