// Ray tracer of melting ice on a wet ground (integrator/ice_surface.h).

#include <meltlab/render/integrator/ice_surface.h>
#include <meltlab/render/fog/scene_fog.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace meltlab::render {

using Eigen::Vector3d;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

IceRenderer::IceRenderer(RenderScene scene) : scene_(std::move(scene)) {
  // Image files named by the scene replace the procedural assets (read through OpenImageIO).
  TextureFactory textures(scene_.texture_filter);
  footprints_ = textures.uses_footprints();
  environment_ = textures.environment(scene_.environment.file.empty()
                                          ? latlong_environment(scene_.environment)
                                          : read_environment(scene_.environment.file, scene_.environment.layout),
                                      "environment");
  ground_texture_ = textures.image(
      scene_.ground.texture_file.empty() ? ground_texture(256, 1) : read_rgb_image(scene_.ground.texture_file),
      "ground texture");
  if (scene_.ice.normal_map)
    normal_map_ = textures.image(scene_.ice.normal_map_file.empty() ? normal_map(256, scene_.ice.normal_map_bump, 2)
                                                                    : read_rgb_image(scene_.ice.normal_map_file),
                                 "normal map");
  if (!scene_.ice.texture_file.empty())
    ice_texture_ = textures.image(read_rgb_image(scene_.ice.texture_file), "ice texture");
  if (scene_.camera) camera_ = scene_.camera;
  if (scene_.fog)
    fog_ = std::make_unique<fog::FogShader>(*scene_.fog, std::vector<double>{scene_.ice.n_spec, scene_.ground.n_spec});
}
IceRenderer::~IceRenderer() = default;

const Camera& IceRenderer::camera() const {
  if (!camera_) throw InvariantError("IceRenderer: no camera before the first set_mesh");
  return *camera_;
}

void IceRenderer::resolve_defaults() {
  if (sized_ || bvh_.empty()) return;
  sized_ = true;
  const Vector3d ext = bvh_.upper() - bvh_.lower();
  object_size_ = std::max({ext.x(), ext.y(), ext.z(), 1e-9});
  if (!(scene_.ice.texture_scale > 0)) scene_.ice.texture_scale = 0.05 * object_size_;
  if (!(scene_.ice.normal_map_tile > 0)) scene_.ice.normal_map_tile = 0.2 * object_size_;
  if (!(scene_.ice.texture_tile > 0)) scene_.ice.texture_tile = 0.2 * object_size_;
  if (!(scene_.ground.tile > 0)) scene_.ground.tile = 0.5 * object_size_;
  if (!scene_.ground.z) scene_.ground.z = bvh_.lower().z();
  if (!camera_) camera_ = auto_camera(bvh_.lower(), bvh_.upper(), scene_.width, scene_.height);
}

template <class Real>
void IceRenderer::set_mesh(const sim::TriMesh<Real>& mesh) {
  stats_.bvh = bvh_.update(mesh);
  stats_.bvh_ms = bvh_.last_update_ms();
  stats_.triangles = bvh_.triangle_count();
  resolve_defaults();
}
template void IceRenderer::set_mesh(const sim::TriMesh<double>&);
template void IceRenderer::set_mesh(const sim::TriMesh<float>&);
void IceRenderer::set_mesh(const sim::IndexedMesh& mesh) {
  stats_.bvh = bvh_.update(mesh);
  stats_.bvh_ms = bvh_.last_update_ms();
  stats_.triangles = bvh_.triangle_count();
  resolve_defaults();
}

ShadingPlan IceRenderer::plan() const {
  const bool lit = !scene_.lights.empty();
  std::vector<std::string> skipped;
  const IcePlan ice = plan_ice(scene_.ice, lit, skipped);
  const GroundPlan ground = plan_ground(scene_.ground, lit, mask_, skipped);
  return ShadingPlan{ice, ground, std::move(skipped)};
}

namespace {

// The first surface along a primary ray (the fog pass needs its distance, point, normal and, on
// the ground, the diffuse colour: the texture, shifted by the liquid, with the ray's footprint).
struct FirstSurface {
  bool hit = false, ice = false;
  double t = 0;
  Vector3d p = Vector3d::Zero(), n = Vector3d::UnitZ();  ///< n: unit, facing the eye
  Rgb diffuse_colour = Rgb(1, 1, 1);
};

// The scene of one frame as the rays see it: the ice (the BVH and its material), the ground
// with its material, the environment. Read-only while the tiles run.
class FrameScene final : public IceSurroundings {
 public:
  FrameScene(const MeshBvh& bvh, const WetGround& ground, const EnvironmentTexture& environment, double ground_z,
             double eps, double ground_far)
      : bvh_(bvh),
        ground_(ground),
        environment_(environment),
        ground_z_(ground_z),
        eps_(eps),
        ground_far_(ground_far) {}

  /// How far secondary rays start off the surface they leave.
  double eps() const { return eps_; }

  // Radiance along the primary ray o + t·d (d unit) with `ice` the ice's material; `rd` the
  // ray's footprint or nullptr; `first` (if given) receives the first surface (for the fog pass).
  Rgb primary_radiance(const IceShader& ice, const Vector3d& o, const Vector3d& d, const RayDifferential* rd,
                       FirstSurface* first = nullptr) const {
    MeshHit h;
    const double t_ground = ground_t(o, d);
    const bool on_ice = bvh_.intersect(o, d, 0.0, t_ground, h);
    if (first) {
      *first = FirstSurface{};
      if (on_ice) {
        const Vector3d n = bvh_.shading_normal(h);
        *first = FirstSurface{true, true, h.t, o + h.t * d, n.dot(d) > 0 ? Vector3d(-n) : n};
      } else if (t_ground < ground_far_) {
        const Vector3d q = o + t_ground * d;
        const Differential dq = rd ? plane_footprint(o, d, *rd, q, Vector3d::UnitZ(), ground_far_) : Differential{};
        const WetGround::FogSurface g = ground_.fog_surface(q, d, rd ? &dq : nullptr);
        *first = FirstSurface{true, false, t_ground, q, g.normal, g.diffuse_colour};
      }
    }
    if (!on_ice) return background(o, d, rd);
    SurfaceHit hit{o + h.t * d, h.ng, bvh_.shading_normal(h), {}};
    if (!rd) return ice.shade(hit, d, nullptr);
    // The footprint at the hit: where the neighbouring rays meet the triangle's plane.
    const RayDifferential at_hit{plane_footprint(o, d, *rd, hit.p, h.ng, ground_far_), rd->d};
    hit.dn = {bvh_.shading_normal_differential(h, at_hit.o.dx), bvh_.shading_normal_differential(h, at_hit.o.dy)};
    return ice.shade(hit, d, &at_hit);
  }

  // ---- IceSurroundings: what the physical ice asks ----
  std::optional<SurfaceCrossing> next_crossing(const Vector3d& o, const Vector3d& d, double t_min) const override {
    MeshHit e;
    if (!bvh_.intersect(o, d, t_min, kInf, e)) return std::nullopt;
    return SurfaceCrossing{e.t, bvh_.shading_normal(e)};
  }
  Rgb radiance_outside(const Vector3d& o, const Vector3d& d, const RayDifferential* rd) const override {
    MeshHit h;
    if (bvh_.intersect(o, d, eps_, ground_t(o, d), h)) return environment_.lookup(d, rd ? &rd->d : nullptr);
    return background(o, d, rd);
  }

 private:
  // Where o + t·d meets the ground plane (kInf if it does not, going down from above it).
  double ground_t(const Vector3d& o, const Vector3d& d) const {
    return (d.z() < 0 && o.z() > ground_z_) ? (ground_z_ - o.z()) / d.z() : kInf;
  }

  // Ground or environment along a ray that does not look at the ice (or after it).
  // Rays almost parallel to the ground meet it at the horizon: beyond ground_far they see the
  // environment (this also keeps texel coordinates far inside the range of int).
  Rgb background(const Vector3d& o, const Vector3d& d, const RayDifferential* rd) const {
    if (d.z() < 0 && o.z() > ground_z_) {
      const double t = (ground_z_ - o.z()) / d.z();
      if (t < ground_far_) {
        const Vector3d q = o + t * d;
        const Differential dq = rd ? plane_footprint(o, d, *rd, q, Vector3d::UnitZ(), ground_far_) : Differential{};
        return ground_.shade(q, d, rd ? &dq : nullptr, rd ? &rd->d : nullptr);
      }
    }
    return environment_.lookup(d, rd ? &rd->d : nullptr);
  }

  const MeshBvh& bvh_;
  const WetGround& ground_;
  const EnvironmentTexture& environment_;
  double ground_z_;
  double eps_;         ///< offset of secondary rays from the surface they leave
  double ground_far_;  ///< beyond this the ground is the horizon: the environment
};

}  // namespace

RgbImage IceRenderer::render() {
  const auto t0 = std::chrono::steady_clock::now();
  if (!camera_) {
    if (!scene_.camera)
      camera_ = auto_camera(Vector3d(-1, -1, 0), Vector3d(1, 1, 1), scene_.width, scene_.height);
    else
      camera_ = scene_.camera;
  }
  const ShadingPlan p = plan();
  std::string log = fmt::format("{}", fmt::join(p.skipped, "; "));
  if (log != last_plan_log_) {
    spdlog::info("render: skipped: {}", log.empty() ? "nothing" : log);
    last_plan_log_ = log;
  }
  // The materials of this frame and the scene their rays see.
  std::vector<Light> lights;
  for (const auto& l : scene_.lights) lights.push_back({l.to_light.normalized(), l.colour});
  const double ground_z = scene_.ground.z.value_or(0.0);
  const WetGround ground(scene_.ground, p, lights, *ground_texture_, *environment_, mask_);
  const FrameScene frame(bvh_, ground, *environment_, ground_z, 1e-4 * object_size_, 1e6 * object_size_);
  const IceTextures ice_textures{environment_.get(), normal_map_.get(), ice_texture_.get()};
  std::unique_ptr<const IceShader> ice;
  if (scene_.ice.model == IceModel::kMonograph)
    ice = std::make_unique<MonographIce>(scene_.ice, p, ice_textures, lights);
  else
    ice = std::make_unique<PhysicalIce>(scene_.ice, p, ice_textures, frame, frame.eps());
  // The rays.
  const Camera& cam = *camera_;
  const int w = camera_width(cam), h = camera_height(cam);
  const double z_top = std::max(bvh_.upper().z(), ground_z) + object_size_;
  const RayGenerator rays(cam, z_top);
  RgbImage img = rgb_image(w, h);
  const fog::FogMaterial fog_ice = fog::FogShader::material(scene_.ice.cd, scene_.ice.cs, scene_.ice.n_spec);
  const fog::FogMaterial fog_ground =
      fog::FogShader::material(scene_.ground.cd, scene_.ground.cs, scene_.ground.n_spec);
  tbb::parallel_for(tbb::blocked_range2d<int>(0, h, 16, 0, w, 16), [&](const tbb::blocked_range2d<int>& r) {
    for (int j = r.rows().begin(); j < r.rows().end(); ++j)
      for (int i = r.cols().begin(); i < r.cols().end(); ++i) {
        const CameraRay ray = rays.generate_ray(i, j);
        if (!ray.ok) {
          set_rgb(img, i, j, Rgb::Zero());
          continue;
        }
        // The footprint: the rays through the next pixel to the right and below. A neighbour
        // whose undistortion did not converge gives no footprint (finest level).
        RayDifferential rd;
        bool has_rd = false;
        if (footprints_) {
          const CameraRay rx = rays.generate_ray(i + 1, j);
          const CameraRay ry = rays.generate_ray(i, j + 1);
          rd = {{rx.origin - ray.origin, ry.origin - ray.origin},
                {rx.direction - ray.direction, ry.direction - ray.direction}};
          has_rd = rx.ok && ry.ok;
        }
        if (!fog_) {
          set_rgb(img, i, j, frame.primary_radiance(*ice, ray.origin, ray.direction, has_rd ? &rd : nullptr));
          continue;
        }
        // The fog pass on the shaded pixel; on the ground its surface terms take the texture's
        // colour (with the same footprint) and the liquid's normal.
        FirstSurface first;
        const Rgb c = frame.primary_radiance(*ice, ray.origin, ray.direction, has_rd ? &rd : nullptr, &first);
        fog::FogMaterial ground_here = fog_ground;
        ground_here.diffuse_colour = first.diffuse_colour;
        const fog::SurfaceHit hit{first.p, first.n, first.ice ? &fog_ice : &ground_here};
        set_rgb(img, i, j, fog_->apply(c, ray.origin, ray.direction, first.t, first.hit ? &hit : nullptr));
      }
  });
  stats_.trace_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return img;
}

}  // namespace meltlab::render
