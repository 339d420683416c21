// The two-pass fog frame (render/fog/fog_frame.h): the visibility pass against closed forms and
// against Embree over the same scene as a mesh, the shading pass against the per-ray model.

#include <meltlab/render/fog/fog_frame.h>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace meltlab::render::fog {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(FogFrame, AnalyticVisibilityHitsTheSphereAndThePlaneWhereTheyAre) {
  const FogScene s = scene_sphere(0.1, 64, 48);
  const GBuffer g = trace_analytic(s);
  ASSERT_EQ(g.pixels.size(), std::size_t{64 * 48});
  const Vec3 eye(0, -5, 0.5);
  EXPECT_LT((g.eye - eye).norm(), 1e-12);
  int sphere = 0, plane = 0, miss = 0;
  for (const auto& px : g.pixels) {
    EXPECT_NEAR(px.dir.norm(), 1.0, 1e-12);
    if (!px.hit) {
      ++miss;
      EXPECT_EQ(px.m, s.far_m);
      continue;
    }
    // The point lies on the ray at m, and the normal faces the eye.
    EXPECT_LT((px.p - (g.eye + px.m * px.dir)).norm(), 1e-9);
    EXPECT_LT(px.normal.dot(px.dir), 0.0);
    // On the sphere |p| = 1 with normal p, or on the plane z = -1 with normal +z; 1e-9 m covers
    // the rounding of a quadratic's root at distances of a few metres.
    if (std::abs(px.p.norm() - 1) < 1e-9) {
      ++sphere;
      EXPECT_LT((px.normal - px.p).norm(), 1e-9);
    } else {
      ++plane;
      EXPECT_NEAR(px.p.z(), -1.0, 1e-9);
      EXPECT_LT((px.normal - Vec3::UnitZ()).norm(), 1e-12);
    }
  }
  EXPECT_GT(sphere, 0);
  EXPECT_GT(plane, 0);
  EXPECT_GT(miss, 0);  // the horizon: above it the rays end at the far distance
  // The central ray (pixel centres 31.5, 23.5 straddle the axis) hits the sphere at |eye| - 1.
  const double m_axis = eye.norm() - 1;
  EXPECT_NEAR(g.at(32, 24).m, m_axis, 0.05);
}

TEST(FogFrame, EmbreeOverTheSceneMeshAgreesWithTheAnalyticTrace) {
  const FogScene s = scene_sphere(0.1, 80, 60);
  const sim::IndexedMesh mesh = scene_mesh(s, 40000);
  // A UV sphere of about 40k triangles (stacks = √(40000/4) = 100, slices 200), two plane triangles.
  EXPECT_GT(mesh.F.size(), std::size_t{38000});
  EXPECT_LT(mesh.F.size(), std::size_t{42000});
  for (std::size_t v = 0; v + 4 < mesh.V.size(); ++v) EXPECT_NEAR(mesh.V[v].norm(), 1.0, 1e-12);  // sphere first
  MeshBvh bvh;
  bvh.update(mesh);
  const GBuffer a = trace_analytic(s), b = trace_mesh(bvh, s.camera, s.far_m);
  int differ = 0, compared = 0;
  for (std::size_t k = 0; k < a.pixels.size(); ++k) {
    const auto &pa = a.pixels[k], &pb = b.pixels[k];
    EXPECT_LT((pa.dir - pb.dir).norm(), 1e-12);
    if (pa.hit != pb.hit || std::abs(pa.m - pb.m) > 0.05) {
      ++differ;  // silhouette pixels: the polygon and the sphere disagree there
      continue;
    }
    if (!pa.hit) continue;
    ++compared;
    if (std::abs(pa.p.norm() - 1) < 1e-9) {
      // The mesh is inscribed: its hit lies behind the sphere's, at most the facets' depth inside
      // it. A quad of 100 stacks × 200 slices spans δ = π/100 each way; the centre of its diagonal
      // lies 1 - cos(δ/√2) ≈ δ²/4 = 2.5e-4 below the sphere; float vertices add ~1e-7.
      EXPECT_GE(pb.m, pa.m - 1e-6);
      EXPECT_LE(1 - pb.p.norm(), 3e-4);
      EXPECT_GE(1 - pb.p.norm(), -1e-6);
      // Interpolated vertex normals against the exact ones: within the facet angle π/100.
      EXPECT_GT(pa.normal.dot(pb.normal), std::cos(kPi / 100));
    } else {
      // The plane as two float triangles 1 km across: float positions (~3e-5 m at 500 m).
      EXPECT_NEAR(pb.p.z(), -1.0, 1e-4);
      EXPECT_LT((pa.normal - pb.normal).norm(), 1e-6);
    }
  }
  EXPECT_GT(compared, 2000);
  EXPECT_LT(differ, 40);  // a few silhouette pixels of 4800
}

TEST(FogFrame, ShadingIsThePerRayModelAtEveryPixel) {
  const FogScene s = scene_street(0.04, 48, 36, 3);
  const GBuffer g = trace_analytic(s);
  TableOptions to;
  to.n = 32;
  const FogTableSet tables = build_fog_tables(to, TableFunction::kH, s.material.n);
  const FogFunctions fn = tables.functions();
  ASSERT_NE(fn.h, nullptr);
  EXPECT_EQ(fn.f, nullptr);
  ASSERT_NE(fn.g_diffuse, nullptr);
  ASSERT_NE(fn.g_specular, nullptr);
  const FogModelOptions o;
  ShadeStats stats;
  const ImageF img = shade_fog(g, s, fn, o, &stats);
  ASSERT_EQ(img.width(), 48);
  ASSERT_EQ(img.height(), 36);
  std::int64_t lit = 0, lookups = 0;
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) {
      const auto& px = g.at(i, j);
      const SurfaceHit hit{px.p, px.normal, &s.material};
      LookupCounts counts;
      const Rgb c = fog_radiance(g.eye, px.dir, px.m, px.hit ? &hit : nullptr, s.lights, s.medium, fn, o, &counts);
      lookups += counts.lookups;
      if (c.maxCoeff() > 0) ++lit;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(img.at(i, j, k), static_cast<float>(c[k])) << i << " " << j;
    }
  EXPECT_EQ(stats.lit_pixels, lit);
  EXPECT_EQ(stats.lookups.lookups, lookups);
  EXPECT_GT(lit, 0);
  EXPECT_LT(lit, 48 * 36);  // the dark sky between the cones
}

TEST(FogFrame, ZeroExtinctionLeavesOnlyTheLitSurface) {
  // k_t = 0: no airlight, no scattered surface light; the pixels that stay lit are exactly the
  // surface points inside the cone (those facing the light certainly).
  const FogScene s = scene_sphere(0.0, 64, 48);
  const GBuffer g = trace_analytic(s);
  TableOptions to;
  to.n = 16;
  const FogTableSet tables = build_fog_tables(to, TableFunction::kF, s.material.n);
  const ImageF img = shade_fog(g, s, tables.functions(), FogModelOptions{});
  for (int j = 0; j < g.height; ++j)
    for (int i = 0; i < g.width; ++i) {
      const auto& px = g.at(i, j);
      const Vec3 to_light = s.lights[0].position - px.p;
      // Phong's specular lobe needs no N·L > 0: a point in the cone facing away may still get a
      // (tiny) highlight, so only the points outside the cone must be black.
      const bool in_cone = px.hit && s.lights[0].intensity_at(px.p) > 0;
      if (!in_cone) {
        EXPECT_EQ(img.at(i, j, 0), 0.0f) << i << " " << j;
      } else if (px.normal.dot(to_light.normalized()) > 1e-3) {
        EXPECT_GT(img.at(i, j, 0), 0.0f) << i << " " << j;
      }
    }
}

TEST(FogFrame, TableSetDescribesItsDomainsAndWarps) {
  TableOptions to;
  to.n = 16;
  to.u_warp = AxisWarp::kSqrt;
  const FogTableSet t = build_fog_tables(to, TableFunction::kF, 20, false);
  const auto lines = t.describe();
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(lines[0], "fsa.table.function = F");
  EXPECT_NE(lines[1].find("warp sqrt"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("16 nodes"), std::string::npos) << lines[1];
  const FogFunctions fn = t.functions();
  EXPECT_EQ(fn.f, &t.airlight);
  EXPECT_EQ(fn.g_diffuse, nullptr);  // with_g = false: the accurate G
}

}  // namespace
}  // namespace meltlab::render::fog
