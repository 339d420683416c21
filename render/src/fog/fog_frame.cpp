// Two-pass frames of seed 002's fog model (fog/fog_frame.h).

#include <meltlab/render/fog/fog_frame.h>

#include <meltlab/core/error.h>

#include <fmt/format.h>
#include <tbb/combinable.h>

#include <chrono>
#include <cmath>
#include <numbers>

namespace meltlab::render::fog {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMinT = 1e-9;  // hits closer than this to the eye are ignored (m)

struct Hit {
  double t = kInf;
  Vec3 normal = Vec3::UnitZ();
};

void hit_sphere(const AnalyticSphere& s, const Vec3& o, const Vec3& d, Hit& h) {
  const Vec3 oc = o - s.centre;
  const double b = oc.dot(d), c = oc.squaredNorm() - s.radius * s.radius;
  const double disc = b * b - c;
  if (disc < 0) return;
  const double r = std::sqrt(disc);
  for (double t : {-b - r, -b + r})
    if (t > kMinT && t < h.t) {
      h.t = t;
      h.normal = (o + t * d - s.centre) / s.radius;
      return;
    }
}

void hit_plane(const AnalyticPlane& p, const Vec3& o, const Vec3& d, Hit& h) {
  const double den = p.normal.dot(d);
  if (std::abs(den) < 1e-15) return;
  const double t = (p.offset - p.normal.dot(o)) / den;
  if (t > kMinT && t < h.t) {
    h.t = t;
    h.normal = p.normal;
  }
}

void hit_post(const AnalyticPost& p, const Vec3& o, const Vec3& d, Hit& h) {
  const double ox = o.x() - p.x, oy = o.y() - p.y;
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a < 1e-15) return;
  const double b = ox * d.x() + oy * d.y(), c = ox * ox + oy * oy - p.radius * p.radius;
  const double disc = b * b - a * c;
  if (disc < 0) return;
  const double r = std::sqrt(disc);
  for (double t : {(-b - r) / a, (-b + r) / a}) {
    const double z = o.z() + t * d.z();
    if (t > kMinT && t < h.t && z >= p.z0 && z <= p.z1) {
      h.t = t;
      h.normal = Vec3(ox + t * d.x(), oy + t * d.y(), 0) / p.radius;
      return;
    }
  }
}

GBuffer make_gbuffer(const Pinhole& camera) {
  GBuffer g;
  g.width = camera.width;
  g.height = camera.height;
  g.eye = camera.camera_from_world.inverse().translation();
  g.pixels.resize(static_cast<std::size_t>(g.width) * g.height);
  return g;
}

template <class HitFn>
GBuffer trace(const Pinhole& camera, double far_m, HitFn hit_fn) {
  GBuffer g = make_gbuffer(camera);
  const RayGenerator rays{Camera(camera)};
  tbb::parallel_for(0, g.height, [&](int j) {
    for (int i = 0; i < g.width; ++i) {
      const CameraRay ray = rays.generate_ray(i, j);
      GBufferPixel& px = g.pixels[static_cast<std::size_t>(j) * g.width + i];
      px.dir = ray.direction;
      Hit h;
      h.t = far_m;
      hit_fn(ray.origin, ray.direction, h);
      px.hit = h.t < far_m;
      px.m = h.t;
      if (px.hit) {
        px.p = ray.origin + h.t * ray.direction;
        px.normal = h.normal.dot(ray.direction) > 0 ? Vec3(-h.normal) : h.normal;
      }
    }
  });
  return g;
}

}  // namespace

const char* table_function_name(TableFunction f) { return f == TableFunction::kF ? "F" : "H"; }

FogFunctions FogTableSet::functions() const {
  FogFunctions fn;
  if (function == TableFunction::kF)
    fn.f = &airlight;
  else
    fn.h = &airlight;
  if (!g_diffuse.values.empty()) fn.g_diffuse = &g_diffuse;
  if (!g_specular.values.empty()) fn.g_specular = &g_specular;
  return fn;
}

std::vector<std::string> FogTableSet::describe() const {
  std::vector<std::string> out{fmt::format("fsa.table.function = {}", table_function_name(function)),
                               airlight.describe()};
  if (!g_diffuse.values.empty()) out.push_back(g_diffuse.describe() + " (the spec's G_0)");
  if (!g_specular.values.empty()) out.push_back(g_specular.describe());
  out.push_back(fmt::format("tables built in {:.1f} ms", build_ms));
  return out;
}

FogTableSet build_fog_tables(const TableOptions& o, TableFunction function, int phong_n, bool with_g) {
  const auto t0 = std::chrono::steady_clock::now();
  FogTableSet s;
  s.options = o;
  s.function = function;
  s.airlight = function == TableFunction::kF ? f_table(o) : h_table(o);
  if (with_g) {
    s.g_diffuse = g_table(1, o);
    s.g_specular = g_table(phong_n, o);
  }
  s.build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

GBuffer trace_analytic(const FogScene& scene) {
  return trace(scene.camera, scene.far_m, [&](const Vec3& o, const Vec3& d, Hit& h) {
    for (const auto& s : scene.spheres) hit_sphere(s, o, d, h);
    for (const auto& p : scene.planes) hit_plane(p, o, d, h);
    for (const auto& p : scene.posts) hit_post(p, o, d, h);
  });
}

GBuffer trace_mesh(const MeshBvh& bvh, const Pinhole& camera, double far_m) {
  return trace(camera, far_m, [&](const Vec3& o, const Vec3& d, Hit& h) {
    MeshHit mh;
    if (bvh.intersect(o, d, kMinT, h.t, mh)) {
      h.t = mh.t;
      h.normal = bvh.shading_normal(mh);
    }
  });
}

sim::IndexedMesh scene_mesh(const FogScene& scene, int sphere_triangles, double plane_half_size) {
  sim::IndexedMesh m;
  auto vertex = [&](const Vec3& p) {
    m.V.push_back(p);
    return static_cast<sim::Index>(m.V.size() - 1);
  };
  for (const auto& s : scene.spheres) {
    const int stacks = std::max(3, static_cast<int>(std::lround(std::sqrt(sphere_triangles / 4.0))));
    const int slices = 2 * stacks;
    const sim::Index top = vertex(s.centre + s.radius * Vec3::UnitZ());
    const sim::Index first = static_cast<sim::Index>(m.V.size());
    for (int i = 1; i < stacks; ++i)
      for (int j = 0; j < slices; ++j) {
        const double th = kPi * i / stacks, ph = 2 * kPi * j / slices;
        vertex(s.centre + s.radius * Vec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
      }
    const sim::Index bottom = vertex(s.centre - s.radius * Vec3::UnitZ());
    auto at = [&](int i, int j) { return first + static_cast<sim::Index>((i - 1) * slices + (j % slices)); };
    for (int j = 0; j < slices; ++j) {
      m.F.push_back({top, at(1, j), at(1, j + 1)});
      m.F.push_back({bottom, at(stacks - 1, j + 1), at(stacks - 1, j)});
    }
    for (int i = 1; i + 1 < stacks; ++i)
      for (int j = 0; j < slices; ++j) {
        m.F.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
        m.F.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
      }
  }
  for (const auto& p : scene.planes) {
    const Vec3 n = p.normal.normalized();
    const Vec3 a = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    const Vec3 e1 = (a - n * n.dot(a)).normalized(), e2 = n.cross(e1);
    const Vec3 c = p.offset * n;
    const sim::Index v0 = vertex(c + plane_half_size * (-e1 - e2)), v1 = vertex(c + plane_half_size * (e1 - e2));
    const sim::Index v2 = vertex(c + plane_half_size * (e1 + e2)), v3 = vertex(c + plane_half_size * (-e1 + e2));
    m.F.push_back({v0, v1, v2});
    m.F.push_back({v0, v2, v3});
  }
  for (const auto& p : scene.posts) {
    constexpr int kSides = 16;
    const sim::Index first = static_cast<sim::Index>(m.V.size());
    for (int k = 0; k < kSides; ++k) {
      const double a = 2 * kPi * k / kSides;
      vertex(Vec3(p.x + p.radius * std::cos(a), p.y + p.radius * std::sin(a), p.z0));
      vertex(Vec3(p.x + p.radius * std::cos(a), p.y + p.radius * std::sin(a), p.z1));
    }
    for (int k = 0; k < kSides; ++k) {
      const sim::Index b0 = first + 2 * k, t0 = b0 + 1;
      const sim::Index b1 = first + 2 * ((k + 1) % kSides), t1 = b1 + 1;
      m.F.push_back({b0, b1, t1});
      m.F.push_back({b0, t1, t0});
    }
  }
  return m;
}

ImageF shade_fog(const GBuffer& g, const FogScene& scene, const FogFunctions& fn, const FogModelOptions& o,
                 ShadeStats* stats) {
  tbb::combinable<ShadeStats> local;
  ImageF img = shade_with(g, [&](const GBufferPixel& px) {
    ShadeStats& st = local.local();
    const SurfaceHit hit{px.p, px.normal, &scene.material};
    const Rgb c =
        fog_radiance(g.eye, px.dir, px.m, px.hit ? &hit : nullptr, scene.lights, scene.medium, fn, o, &st.lookups);
    if (c.maxCoeff() > 0) ++st.lit_pixels;
    return c;
  });
  if (stats) {
    *stats = ShadeStats{};
    local.combine_each([&](const ShadeStats& s) {
      stats->lookups += s.lookups;
      stats->lit_pixels += s.lit_pixels;
    });
  }
  return img;
}

}  // namespace meltlab::render::fog
