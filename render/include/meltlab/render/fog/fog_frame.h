#pragma once
// A frame of seed 002's fog model in two passes, as the thesis's deferred shader: visibility
// (per pixel the view ray, the distance m to the first surface and its point and normal) into a
// G-buffer, then the shading pass (fog/airlight.h's fog_radiance per pixel, TBB tiles of 16×16)
// that never touches the geometry again: its cost is per pixel and per light, independent of
// the triangle count (spec §6 target 9). Visibility by exact ray casting of the analytic scenes
// of fog/scenes.h, or by Embree over a triangle mesh (render/embree/mesh_bvh.h).

#include <meltlab/core/image.h>
#include <meltlab/render/camera.h>
#include <meltlab/render/embree/mesh_bvh.h>
#include <meltlab/render/fog/scenes.h>

#include <limits>
#include <string>
#include <vector>

namespace meltlab::render::fog {

struct GBufferPixel {
  Vec3 dir = Vec3::UnitX();                            ///< unit view direction (world)
  double m = std::numeric_limits<double>::infinity();  ///< distance to the surface, or the far distance
  bool hit = false;                               ///< a surface at m (else the ray ends at the scene's far distance)
  Vec3 p = Vec3::Zero(), normal = Vec3::UnitZ();  ///< the surface point and its unit normal facing the eye
};

struct GBuffer {
  int width = 0, height = 0;
  Vec3 eye = Vec3::Zero();
  std::vector<GBufferPixel> pixels;  ///< row-major, row 0 at the top
  const GBufferPixel& at(int i, int j) const { return pixels[static_cast<std::size_t>(j) * width + i]; }
};

/// Visibility of an analytic scene (spheres, planes, posts), rays through pixel centres.
GBuffer trace_analytic(const FogScene& scene);

/// Visibility by Embree over `bvh` (its smooth shading normals), ending at `far_m`.
GBuffer trace_mesh(const MeshBvh& bvh, const Pinhole& camera, double far_m);

/// A triangle mesh of an analytic scene (spheres as UV spheres with about `sphere_triangles`
/// triangles, planes as two triangles 2·`plane_half_size` across, posts as 16-sided prisms) for
/// trace_mesh.
sim::IndexedMesh scene_mesh(const FogScene& scene, int sphere_triangles, double plane_half_size = 500);

/// The tables of a frame (fsa.table.*): F or H for the airlight, G_1 (the spec's G_0) and G_n.
enum class TableFunction {
  kF,  ///< the source's F(u, v): A0 [F(A1, v_b) - F(A1, v_a)]
  kH,  ///< the harness's tail H(u, v) (airlight_f.h): no cancellation behind the foot point
};
const char* table_function_name(TableFunction f);

struct FogTableSet {
  TableOptions options;
  TableFunction function = TableFunction::kH;
  FogTable airlight;  ///< F or H
  FogTable g_diffuse, g_specular;
  double build_ms = 0;  ///< wall time of building the three tables

  /// The F/G pointers for the model (the airlight table as F or H).
  FogFunctions functions() const;
  /// One line per table (domains, axis warps, sizes) for the run record.
  std::vector<std::string> describe() const;
};

/// Builds the airlight table and the G tables of exponents 1 and `phong_n` (G_n skipped when
/// `with_g` is false: the airlight-only studies).
FogTableSet build_fog_tables(const TableOptions& o, TableFunction function, int phong_n, bool with_g = true);

struct ShadeStats {
  LookupCounts lookups;
  std::int64_t lit_pixels = 0;  ///< pixels with a nonzero result
};

/// The shading pass: fog_radiance per pixel of `g` (linear RGB, g.width × g.height).
ImageF shade_fog(const GBuffer& g, const FogScene& scene, const FogFunctions& fn, const FogModelOptions& o,
                 ShadeStats* stats = nullptr);

/// A per-pixel reference or peer for the error studies: f(pixel) -> RGB, in parallel.
template <class PixelFn>
ImageF shade_with(const GBuffer& g, PixelFn f);

}  // namespace meltlab::render::fog

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

namespace meltlab::render::fog {

template <class PixelFn>
ImageF shade_with(const GBuffer& g, PixelFn f) {
  ImageF img(g.width, g.height, 3);
  tbb::parallel_for(tbb::blocked_range2d<int>(0, g.height, 16, 0, g.width, 16),
                    [&](const tbb::blocked_range2d<int>& r) {
                      for (int j = r.rows().begin(); j < r.rows().end(); ++j)
                        for (int i = r.cols().begin(); i < r.cols().end(); ++i) {
                          const Rgb c = f(g.at(i, j));
                          for (int k = 0; k < 3; ++k) img.at(i, j, k) = static_cast<float>(c[k]);
                        }
                    });
  return img;
}

}  // namespace meltlab::render::fog
