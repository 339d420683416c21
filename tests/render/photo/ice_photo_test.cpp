// Photo-like ice renderer (render/integrator/ice_photo.h): closed-form slabs (Beer–Lambert, shadowed
// ground, single scattering with the HG phase), ground texture through thin/thick ice,
// determinism, camera geometry against the mesh rasterizer, and the segmentation round trip.

#include <meltlab/datasets/procedural.h>
#include <meltlab/render/integrator/ice_photo.h>
#include <meltlab/render/raster/silhouette.h>
#include <meltlab/core/error.h>
#include <meltlab/verify/metrics.h>
#include <meltlab/verify/observations.h>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>

#include <unistd.h>

namespace meltlab::render {
namespace {

using sim::physics::IceFraction;
using Shadow = IcePhotoOptions::Shadow;

// Grid covering [x0, x1] x [y0, y1] x [0, z1] (metres) with cell size h, all air.
IceFraction grid(double x0, double x1, double y0, double y1, double z1, double h) {
  return IceFraction(int(std::lround((x1 - x0) / h)), int(std::lround((y1 - y0) / h)), int(std::lround(z1 / h)), h,
                     Vec3d(x0, y0, 0.0), 0.0f);
}

// Cells whose centres satisfy `inside` become ice (fraction 1).
template <class F>
void fill(IceFraction& g, const F& inside) {
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i)
        if (inside(g.centre_m(i, j, k))) g.at(i, j, k) = 1.0f;
}

// Axis-aligned box mesh [x0, x1] x [y0, y1] x [0, h].
sim::IndexedMesh box_mesh(double x0, double x1, double y0, double y1, double h) {
  sim::IndexedMesh m = datasets::cube_triangles(1.0);
  for (auto& p : m.V) {
    p.x() = p.x() < 0 ? x0 : x1;
    p.y() = p.y() < 0 ? y0 : y1;
    p.z() = p.z() < 0 ? 0.0 : h;
  }
  return m;
}

// Orthographic camera looking straight down at (0, 0): 21 x 21 px, 0.1 mm per px.
Camera small_ortho() { return OrthographicTopDown::from_pixels_per_mm(21, 21, 10.0, Vec2d(0, 0)); }

// Options isolating one term: no texture, no blur, no noise.
IcePhotoOptions plain() {
  IcePhotoOptions o;
  o.ground_texture_contrast = 0;
  o.lens_blur_sigma_px = 0;
  o.noise_sigma = 0;
  o.ice_tint_rgb = {1, 1, 1};
  o.ground_tint_rgb = {1, 1, 1};
  return o;
}

double centre_value(const cv::Mat& radiance, int channel = 1) {
  return radiance.at<cv::Vec3f>(radiance.rows / 2, radiance.cols / 2)[channel];
}

// A homogeneous wide slab of thickness d filling the grid: f = 1 up to the grid's top face.
IceFraction slab(double d, double h = 0.5e-3) {
  IceFraction g = grid(-0.01, 0.01, -0.01, 0.01, d, h);
  std::fill(g.value.begin(), g.value.end(), 1.0f);
  return g;
}

TEST(IcePhoto, HenyeyGreensteinIsNormalisedWithMeanCosineG) {
  // Midpoint quadrature in cosθ with 200000 nodes: error ~1e-7 for |g| = 0.9 (the sharp lobe;
  // 1e-5 at 20000 nodes, shrinking as 1/n²).
  for (double g : {-0.9, -0.5, 0.0, 0.3, 0.9}) {
    const int n = 200000;
    double s0 = 0, s1 = 0;
    for (int i = 0; i < n; ++i) {
      const double mu = -1.0 + (i + 0.5) * 2.0 / n;
      const double p = henyey_greenstein(mu, g) * 2.0 * std::numbers::pi * (2.0 / n);
      s0 += p;
      s1 += p * mu;
    }
    EXPECT_NEAR(s0, 1.0, 1e-6) << "g = " << g;
    EXPECT_NEAR(s1, g, 1e-6) << "g = " << g;
  }
  EXPECT_NEAR(henyey_greenstein(0.3, 0.0), 1.0 / (4.0 * std::numbers::pi), 1e-15);
}

TEST(IcePhoto, AbsorptionSlabIsBeerLambertAndDecreasesWithThickness) {
  // No scattering, no shadows, sky-lit uniform ground: I = ρ·sky·exp(-σ d). The midpoint rule
  // with the exponential integrator is exact for a homogeneous slab; the only error is float
  // rounding of the CV_32F output (relative 1e-6).
  IcePhotoOptions o = plain();
  o.albedo = 0;
  o.shadow = Shadow::kNone;
  o.lamp_irradiance = 0;
  o.sky_radiance = 1.0;
  o.ground_albedo = 0.2;
  o.extinction_per_m = 150;
  double previous = 1e9;
  for (double d : {0.5e-3, 2e-3, 5e-3, 10e-3, 20e-3}) {
    const cv::Mat r = render_ice_radiance(slab(d), small_ortho(), o);
    const double expected = 0.2 * std::exp(-150.0 * d);
    const double got = centre_value(r);
    EXPECT_NEAR(got / expected, 1.0, 1e-6) << "d = " << d;
    EXPECT_LT(got, previous);
    previous = got;
  }
  // Bare ground (extinction 0) is exactly ρ·sky.
  o.extinction_per_m = 0;
  EXPECT_NEAR(centre_value(render_ice_radiance(slab(5e-3), small_ortho(), o)), 0.2, 1e-7);
}

TEST(IcePhoto, ShadowedGroundUnderSlabMatchesClosedForm) {
  // Lamp only, ground shadow ray through the slab at cos θ = μ: I = ρ/π·μ·L·e^{-σd/μ}·e^{-σd}.
  // The shadow march is exact for a homogeneous medium as well; float rounding only.
  IcePhotoOptions o = plain();
  o.albedo = 0;
  o.sky_radiance = 0;
  o.ground_albedo = 0.3;
  o.to_lamp = Vec3d(std::sin(0.5), 0.0, std::cos(0.5));
  const double mu = std::cos(0.5), d = 4e-3, sigma = o.extinction_per_m;
  for (Shadow s : {Shadow::kGrid, Shadow::kMarch}) {
    o.shadow = s;
    const double expected = 0.3 / std::numbers::pi * mu * std::exp(-sigma * d / mu) * std::exp(-sigma * d);
    EXPECT_NEAR(centre_value(render_ice_radiance(slab(d), small_ortho(), o)) / expected, 1.0, 1e-5);
  }
}

TEST(IcePhoto, SingleScatterThinSlabMatchesHandComputedHG) {
  // Spec target 7 (HGAttenuated) with κ in the BRDF (r = a σ p): viewed straight down, lamp at
  // polar angle θ (μ = cos θ), black ground, no sky:
  //   I = a p L (1 - e^{-σH(1+1/μ)}) / (1 + 1/μ),   p = p_HG(cos = -μ, g).
  // Hand value: a = 0.9, g = 0.3, L = 2, θ = 30°, σ = 150/m, H = 3 mm:
  //   p = (1/4π)·0.91/(1.09 + 0.6·0.866025)^1.5 = 0.0354608, k = 1 + 1/μ = 2.154701,
  //   1 - e^{-0.45·2.154701} = 0.620771 → I = 0.9·0.0354608·2·0.620771/2.154701 = 0.0183893.
  IcePhotoOptions o = plain();
  o.albedo = 0.9;
  o.hg_g = 0.3;
  o.lamp_irradiance = 2.0;
  o.sky_radiance = 0;
  o.ground_albedo = 0;
  o.extinction_per_m = 150;
  const double theta = std::numbers::pi / 6, mu = std::cos(theta), H = 3e-3;
  o.to_lamp = Vec3d(std::sin(theta), 0.0, mu);
  const double p = henyey_greenstein(-mu, 0.3);
  EXPECT_NEAR(p, 0.0354608, 1e-7);
  const double k = 1.0 + 1.0 / mu;
  const double expected = 0.9 * p * 2.0 * (1.0 - std::exp(-150.0 * H * k)) / k;
  EXPECT_NEAR(expected, 0.0183893, 1e-7);
  // kMarch: per-step T_lamp at the step midpoint; error ~ (σΔs/μ)²/24 ≈ 1e-4 relative, so 1e-3.
  o.shadow = Shadow::kMarch;
  EXPECT_NEAR(centre_value(render_ice_radiance(slab(H), small_ortho(), o)) / expected, 1.0, 1e-3);
  // kGrid: T_lamp interpolated linearly between cell centres and clamped in the top half cell
  // (relative error ~ σh/(2μ) over h/2 of the 3 mm path ≈ 0.4% here), so 1%.
  o.shadow = Shadow::kGrid;
  const double grid_value = centre_value(render_ice_radiance(slab(H), small_ortho(), o));
  EXPECT_NEAR(grid_value / expected, 1.0, 1e-2);
  // Unshadowed (spec target 6 with κ in the BRDF): a p L (1 - e^{-σH}), exact.
  o.shadow = Shadow::kNone;
  EXPECT_NEAR(centre_value(render_ice_radiance(slab(H), small_ortho(), o)) / (0.9 * p * 2.0 * (1 - std::exp(-0.45))),
              1.0, 1e-5);
}

TEST(IcePhoto, GroundTextureVisibleThroughThinIceButNotThick) {
  // Step slab: x < 0 is 1 mm thick (σd = 0.15), x > 0 is 25 mm (σd = 3.75). Two renders with
  // different ground seeds: their difference is the ground texture seen through the ice.
  // Radiance: the texture's amplitude is scaled by the view transmittance e^{-σd} times the
  // ground's own illumination through the ice (e^{-σd/μ} for the lamp, e^{-σd} for the sky):
  // through 1 mm ≈ 0.86·0.85 ≈ 0.73 of bare ground (so > 0.65), through 25 mm ≈ e^{-7.8} < 0.01.
  // Photo (no noise, no blur): bare ground differs by ~5 levels on average, thin ice by ~2 (the
  // in-scattered light lifts it where the gamma curve is flatter): > 1; thick ice by < 0.1.
  IceFraction g = grid(-0.02, 0.02, -0.01, 0.01, 0.025, 0.5e-3);
  fill(g, [](const Vec3d& c) { return c.z() < (c.x() < 0 ? 1e-3 : 25e-3) && std::abs(c.x()) < 0.015; });
  IcePhotoOptions o;
  o.lens_blur_sigma_px = 0;
  o.noise_sigma = 0;
  const Camera cam = OrthographicTopDown::from_pixels_per_mm(400, 100, 10.0, Vec2d(0, 0));
  const cv::Mat ra = render_ice_radiance(g, cam, o);
  o.ground_seed = 2;
  const cv::Mat rb = render_ice_radiance(g, cam, o);
  auto mean_diff = [](const cv::Mat& a, const cv::Mat& b, int u0, int u1) {
    cv::Mat d;
    cv::absdiff(a(cv::Rect(u0, 20, u1 - u0, 60)), b(cv::Rect(u0, 20, u1 - u0, 60)), d);
    return cv::mean(d.reshape(1))[0];
  };
  // Columns: bare ground x < -15 mm (u < 50), thin ice -14.5..-11.5 mm (outside the thick
  // part's shadow, which the lamp at +x casts over x ∈ [-10.7, -1] mm), thick ice 1..14 mm.
  // The same two grounds without ice, for the ratios column by column.
  IcePhotoOptions no_ice = o;
  no_ice.extinction_per_m = 0;
  const cv::Mat rb0 = render_ice_radiance(g, cam, no_ice);
  no_ice.ground_seed = 1;
  const cv::Mat ra0 = render_ice_radiance(g, cam, no_ice);
  const double r_thin = mean_diff(ra, rb, 55, 85) / mean_diff(ra0, rb0, 55, 85),
               r_thick = mean_diff(ra, rb, 220, 330) / mean_diff(ra0, rb0, 220, 330);
  const cv::Mat a = develop_photo(ra, o), b = develop_photo(rb, o);
  const double bare = mean_diff(a, b, 5, 40), thin = mean_diff(a, b, 55, 85), thick = mean_diff(a, b, 220, 330);
  std::printf(
      "texture through ice: radiance thin/bare %.3f thick/bare %.5f; photo levels bare %.2f thin %.2f thick %.3f\n",
      r_thin, r_thick, bare, thin, thick);
  EXPECT_GT(r_thin, 0.65);
  EXPECT_LT(r_thin, 0.80);
  EXPECT_LT(r_thick, 0.01);
  EXPECT_GT(bare, 3.0);
  EXPECT_GT(thin, 1.0);
  EXPECT_LT(thick, 0.1);
  // And the thick ice is bright, the ground dark.
  cv::Mat ga;
  cv::cvtColor(a, ga, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::mean(ga(cv::Rect(220, 20, 110, 60)))[0], 180.0);
  EXPECT_LT(cv::mean(ga(cv::Rect(5, 20, 35, 60)))[0], 110.0);
}

IceFraction sphere_grid() {
  IceFraction g = grid(-0.015, 0.015, -0.015, 0.015, 0.025, 0.5e-3);
  fill(g, [](const Vec3d& c) { return (c - Vec3d(0, 0, 0.011)).norm() < 0.01; });
  return g;
}

Pinhole test_pinhole(int w = 160, int h = 120, double fx = 500) {
  return Pinhole::look_at(w, h, fx, Vec3d(0.02, -0.03, 0.25), Vec3d(0, 0, 0.005));
}

bool equal(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

TEST(IcePhoto, DeterministicPerSeedAndSerialEqualsParallel) {
  const IceFraction g = sphere_grid();
  IcePhotoOptions o;
  o.supersample = 2;
  const cv::Mat a = render_ice_photo(g, test_pinhole(), o);
  const cv::Mat b = render_ice_photo(g, test_pinhole(), o);
  EXPECT_TRUE(equal(a, b));
  o.parallel = false;
  const cv::Mat serial = render_ice_photo(g, test_pinhole(), o);
  EXPECT_TRUE(equal(a, serial));
  o.parallel = true;
  o.seed = 7;
  const cv::Mat c = render_ice_photo(g, test_pinhole(), o);
  EXPECT_FALSE(equal(a, c));
  // Only the noise differs: its level is noise_sigma (2 levels) per pixel and channel.
  cv::Mat d;
  cv::absdiff(a, c, d);
  const double mean_abs = cv::mean(d.reshape(1))[0];
  EXPECT_GT(mean_abs, 1.0);  // E|X - Y| = 2σ/√π ≈ 2.26 for two independent N(0, σ²)
  EXPECT_LT(mean_abs, 3.5);
  // The radiance (noise-free) does not depend on the sensor seed at all.
  o.seed = 1;
  const cv::Mat r1 = render_ice_radiance(g, test_pinhole(), o);
  o.seed = 99;
  EXPECT_TRUE(equal(r1, render_ice_radiance(g, test_pinhole(), o)));
}

TEST(IcePhoto, GridShadowsAgreeWithMarchedShadows) {
  // The light-transmittance grid is an approximation of the per-sample shadow march (linear
  // interpolation between cell centres); on a 20 mm sphere with h = 0.5 mm the radiance agrees to
  // a few percent of the ice's brightness (mean well below 1%).
  const IceFraction g = sphere_grid();
  IcePhotoOptions o = plain();
  o.sky_radiance = 0;  // the lamp term only, where shadows matter
  o.shadow = Shadow::kGrid;
  const cv::Mat a = render_ice_radiance(g, test_pinhole(80, 60, 250), o);
  o.shadow = Shadow::kMarch;
  const cv::Mat b = render_ice_radiance(g, test_pinhole(80, 60, 250), o);
  double peak = 0;
  cv::minMaxLoc(b.reshape(1), nullptr, &peak);
  cv::Mat d;
  cv::absdiff(a, b, d);
  double worst = 0;
  cv::minMaxLoc(d.reshape(1), nullptr, &worst);
  const double mean = cv::mean(d.reshape(1))[0];
  std::printf("grid vs march: worst %.4f, mean %.5f of peak %.4f\n", worst / peak, mean / peak, peak);
  EXPECT_LT(worst / peak, 0.05);
  EXPECT_LT(mean / peak, 0.005);
}

// The block: 40 x 40 x 30 mm on the ground, faces on cell faces (h = 0.5 mm).
IceFraction block_grid() {
  IceFraction g = grid(-0.03, 0.03, -0.03, 0.03, 0.035, 0.5e-3);
  fill(g, [](const Vec3d& c) { return std::abs(c.x()) < 0.02 && std::abs(c.y()) < 0.02 && c.z() < 0.03; });
  return g;
}

Pinhole block_camera() {
  Pinhole p = Pinhole::look_at(400, 300, 1400, Vec3d(0.02, -0.03, 0.35), Vec3d(0, 0, 0.01));
  p.distortion = {-0.08, 0.02, 0, 0, 0};
  return p;
}

// Pixels of a XOR b farther than `r` px from the boundary of b.
int xor_beyond(const cv::Mat& a, const cv::Mat& b, int r) {
  cv::Mat x;
  cv::bitwise_xor(a, b, x);
  cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
  cv::Mat dil, ero;
  cv::dilate(b, dil, kernel);
  cv::erode(b, ero, kernel);
  cv::Mat band = dil - ero;
  cv::Mat outside;
  cv::bitwise_and(x, ~band, outside);
  return cv::countNonZero(outside);
}

TEST(IcePhoto, BoxTrueMaskMatchesMeshSilhouetteWithinAPixel) {
  const IceFraction g = block_grid();
  const Pinhole cam = block_camera();
  const cv::Mat truth = ice_true_mask(g, cam);
  const cv::Mat mesh = silhouette_mask(box_mesh(-0.02, 0.02, -0.02, 0.02, 0.03), cam);
  ASSERT_GT(cv::countNonZero(mesh), 20000);
  EXPECT_EQ(xor_beyond(truth, mesh, 1), 0);
  const auto cmp = verify::compare_masks(truth, mesh);
  std::printf("true mask vs mesh silhouette: P = %.4f (%d px)\n", cmp.P, cv::countNonZero(mesh));
  EXPECT_LT(cmp.P, 0.01);
  // Orthographic too.
  const Camera ortho = OrthographicTopDown::from_pixels_per_mm(300, 300, 4.0, Vec2d(0.001, 0));
  EXPECT_EQ(xor_beyond(ice_true_mask(g, ortho), silhouette_mask(box_mesh(-0.02, 0.02, -0.02, 0.02, 0.03), ortho), 1),
            0);
}

TEST(IcePhoto, SegmentedPhotoOfBlockMatchesTrueMask) {
  // The key integration test: the verification loop's default segmentation on the photo of a
  // voxelized block recovers the true outline: P <= 0.05 (the bound the fitting relies on).
  const IceFraction g = block_grid();
  const Pinhole cam = block_camera();
  IcePhotoOptions o;
  o.supersample = 2;
  const cv::Mat photo = render_ice_photo(g, cam, o);
  const auto seg = verify::segment_image(photo, verify::SegmentationSettings{});
  const cv::Mat truth = ice_true_mask(g, cam);
  const auto cmp = verify::compare_masks(seg.mask, truth);
  std::printf("segmented photo vs true mask: P = %.4f (contrast %.1f, threshold %.1f)\n", cmp.P, seg.contrast,
              seg.threshold_used);
  EXPECT_LE(cmp.P, 0.05);
  // The geometry of the photo is the camera's: the segmented outline matches the mesh silhouette.
  const auto mesh = verify::compare_masks(seg.mask, silhouette_mask(box_mesh(-0.02, 0.02, -0.02, 0.02, 0.03), cam));
  EXPECT_LE(mesh.P, 0.05);
}

TEST(IcePhoto, WriteJpegIsAtomicAndHonoursQuality) {
  const IceFraction g = sphere_grid();
  const cv::Mat photo = render_ice_photo(g, test_pinhole(), IcePhotoOptions{});
  const auto dir = std::filesystem::temp_directory_path() / ("meltlab_ice_photo_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  write_jpeg(dir / "q95.jpg", photo, 95);
  write_jpeg(dir / "q20.jpg", photo, 20);
  EXPECT_LT(std::filesystem::file_size(dir / "q20.jpg"), std::filesystem::file_size(dir / "q95.jpg"));
  const cv::Mat back = verify::read_image(dir / "q95.jpg");
  ASSERT_EQ(back.size(), photo.size());
  ASSERT_EQ(back.type(), CV_8UC3);
  cv::Mat d;
  cv::absdiff(back, photo, d);
  EXPECT_LT(cv::mean(d.reshape(1))[0], 3.0);  // q95 JPEG of a smooth image: ~1 level
  // Only the two files: no temporary left behind.
  int files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 2);
  EXPECT_THROW(write_jpeg(dir / "bad.jpg", photo, 0), InputError);
  std::filesystem::remove_all(dir);
}

TEST(IcePhoto, EmptySpaceSkippingDoesNotChangeTheImage) {
  // Skipping only leaves out samples where the fraction (and its interpolant) is exactly 0, and
  // the zenith ground shadow from per-column sums differs from the march by rounding only.
  // Two bodies (a sphere, and a block with a tilted thin plate floating apart from it, so rays
  // cross empty blocks between ice), pinhole with distortion, every shadow mode, supersampled.
  IceFraction g = grid(-0.03, 0.03, -0.03, 0.03, 0.035, 0.5e-3);
  fill(g, [](const Vec3d& c) {
    return (c - Vec3d(-0.012, 0.0, 0.01)).norm() < 0.009 ||
           (std::abs(c.x() - 0.015) < 0.006 && std::abs(c.y()) < 0.02 && std::abs(c.z() - 0.02 - 0.2 * c.y()) < 0.001);
  });
  for (int k = 0; k < g.nz; ++k)  // partial fractions at the sphere's rim
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i)
        if (g.at(i, j, k) > 0 && (g.centre_m(i, j, k) - Vec3d(-0.012, 0.0, 0.01)).norm() > 0.008) g.at(i, j, k) = 0.37f;
  Pinhole cam = test_pinhole(120, 90, 300);
  cam.distortion = {-0.05, 0.01, 0, 0, 0};
  for (Shadow s : {Shadow::kGrid, Shadow::kMarch, Shadow::kNone}) {
    IcePhotoOptions o;
    o.shadow = s;
    o.supersample = s == Shadow::kGrid ? 2 : 1;
    const cv::Mat fast = render_ice_radiance(g, cam, o);
    o.skip_empty_space = false;
    const cv::Mat plain_march = render_ice_radiance(g, cam, o);
    double peak = 0;
    cv::minMaxLoc(plain_march.reshape(1), nullptr, &peak);
    EXPECT_GT(peak, 0.1);
    EXPECT_LE(cv::norm(fast, plain_march, cv::NORM_INF), 1e-6 * peak) << "shadow mode " << int(s);
    o.skip_empty_space = true;
    o.parallel = false;
    EXPECT_TRUE(equal(fast, render_ice_radiance(g, cam, o)));
  }
}

TEST(IcePhoto, RejectsBadInput) {
  IcePhotoOptions o;
  o.to_lamp = Vec3d(1, 0, -0.2);
  EXPECT_THROW(render_ice_radiance(slab(1e-3), small_ortho(), o), InputError);
  EXPECT_THROW(render_ice_radiance(IceFraction{}, small_ortho(), IcePhotoOptions{}), InputError);
}

}  // namespace
}  // namespace meltlab::render
