// Embree BVH over a melting mesh (embree/mesh_bvh.h).

#include <meltlab/render/embree/mesh_bvh.h>
#include <meltlab/core/error.h>

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace meltlab::render {

namespace {
// Embree calls this from C code, so it must not throw: it records the message, and check()
// turns it into an InvariantError after each build step (errors here are programming errors:
// bad buffers or state, never bad input).
void on_embree_error(void* user, RTCError code, const char* message) {
  *static_cast<std::string*>(user) = fmt::format("Embree error {}: {}", static_cast<int>(code), message ? message : "");
}
}  // namespace

struct MeshBvh::Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;
  unsigned geometry_id = RTC_INVALID_GEOMETRY_ID;
  std::string last_error;

  void check() {
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE || !last_error.empty())
      throw InvariantError(last_error.empty() ? std::string("Embree error") : last_error);
  }

  Embree() {
    device = rtcNewDevice(nullptr);
    if (!device)
      throw InvariantError(
          fmt::format("Embree: cannot create a device (error {})", static_cast<int>(rtcGetDeviceError(nullptr))));
    rtcSetDeviceErrorFunction(device, on_embree_error, &last_error);
    scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_DYNAMIC);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
  }
  ~Embree() {
    if (geometry) rtcReleaseGeometry(geometry);
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
  void drop_geometry() {
    if (!geometry) return;
    rtcDetachGeometry(scene, geometry_id);
    rtcReleaseGeometry(geometry);
    geometry = nullptr;
    geometry_id = RTC_INVALID_GEOMETRY_ID;
  }
};

MeshBvh::MeshBvh() : rtc_(std::make_unique<Embree>()) {}
MeshBvh::~MeshBvh() = default;

template <class Real>
BvhUpdate MeshBvh::update(const sim::TriMesh<Real>& mesh) {
  std::vector<float> pos(3 * mesh.vertex_slots() + 1, 0.0f);
  for (std::size_t v = 0; v < mesh.vertex_slots(); ++v)
    for (int k = 0; k < 3; ++k) pos[3 * v + static_cast<std::size_t>(k)] = static_cast<float>(mesh.position[v][k]);
  std::vector<std::uint32_t> idx;
  idx.reserve(3 * mesh.triangle_slots());
  for (std::size_t t = 0; t < mesh.triangle_slots(); ++t) {
    if (!mesh.triangle_alive[t]) continue;
    for (sim::Index v : mesh.triangle[t]) idx.push_back(static_cast<std::uint32_t>(v));
  }
  return load(std::move(pos), std::move(idx));
}

BvhUpdate MeshBvh::update(const sim::IndexedMesh& mesh) {
  std::vector<float> pos(3 * mesh.V.size() + 1, 0.0f);
  for (std::size_t v = 0; v < mesh.V.size(); ++v)
    for (int k = 0; k < 3; ++k) pos[3 * v + static_cast<std::size_t>(k)] = static_cast<float>(mesh.V[v][k]);
  std::vector<std::uint32_t> idx;
  idx.reserve(3 * mesh.F.size());
  for (const auto& f : mesh.F)
    for (sim::Index v : f) idx.push_back(static_cast<std::uint32_t>(v));
  return load(std::move(pos), std::move(idx));
}

template BvhUpdate MeshBvh::update(const sim::TriMesh<double>&);
template BvhUpdate MeshBvh::update(const sim::TriMesh<float>&);

BvhUpdate MeshBvh::load(std::vector<float> positions, std::vector<std::uint32_t> index) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t nv = (positions.size() - 1) / 3, nt = index.size() / 3;
  // Smooth normals: area-weighted sums of the (unnormalised) face normals, then normalised.
  normal_.assign(nv, Eigen::Vector3f::Zero());
  lower_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  upper_ = -lower_;
  auto P = [&](std::uint32_t v) {
    const std::size_t at = std::size_t{3} * v;  // in size_t: 3·v overflows uint32 above 1.4 G vertices
    return Eigen::Vector3f(positions[at], positions[at + 1], positions[at + 2]);
  };
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t a = index[3 * t], b = index[3 * t + 1], c = index[3 * t + 2];
    const Eigen::Vector3f n = (P(b) - P(a)).cross(P(c) - P(a));
    normal_[a] += n;
    normal_[b] += n;
    normal_[c] += n;
    for (std::uint32_t v : {a, b, c}) {
      lower_ = lower_.cwiseMin(P(v).cast<double>());
      upper_ = upper_.cwiseMax(P(v).cast<double>());
    }
  }
  for (auto& n : normal_) {
    const float len = n.norm();
    if (len > 0.0f) n /= len;
  }
  if (nt == 0) lower_ = upper_ = Eigen::Vector3d::Zero();

  BvhUpdate what = BvhUpdate::kRebuild;
  if (nt == 0) {
    rtc_->drop_geometry();
    vertex_ = std::move(positions);
    index_.clear();
    rtcCommitScene(rtc_->scene);
    what = BvhUpdate::kNone;
  } else if (rtc_->geometry && index == index_ && positions.size() == vertex_.size()) {
    // Same triangles: rewrite the shared vertex buffer in place and refit.
    std::copy(positions.begin(), positions.end(), vertex_.begin());
    rtcUpdateGeometryBuffer(rtc_->geometry, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(rtc_->geometry);
    rtcCommitScene(rtc_->scene);
    what = BvhUpdate::kRefit;
  } else {
    rtc_->drop_geometry();
    vertex_ = std::move(positions);
    index_ = std::move(index);
    RTCGeometry g = rtcNewGeometry(rtc_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertex_.data(), 0, 3 * sizeof(float),
                               nv);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, index_.data(), 0,
                               3 * sizeof(std::uint32_t), nt);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);
    rtcCommitGeometry(g);
    rtc_->geometry_id = rtcAttachGeometry(rtc_->scene, g);
    rtc_->geometry = g;
    rtcCommitScene(rtc_->scene);
  }
  rtc_->check();
  last_update_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return what;
}

bool MeshBvh::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_near, double t_far,
                        MeshHit& hit) const {
  if (index_.empty()) return false;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh;
  rh.ray.org_x = static_cast<float>(o.x());
  rh.ray.org_y = static_cast<float>(o.y());
  rh.ray.org_z = static_cast<float>(o.z());
  rh.ray.dir_x = static_cast<float>(d.x());
  rh.ray.dir_y = static_cast<float>(d.y());
  rh.ray.dir_z = static_cast<float>(d.z());
  rh.ray.tnear = static_cast<float>(t_near);
  rh.ray.tfar = static_cast<float>(std::min(t_far, static_cast<double>(std::numeric_limits<float>::max())));
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(rtc_->scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
  hit.t = static_cast<double>(rh.ray.tfar);
  hit.prim = rh.hit.primID;
  hit.u = static_cast<double>(rh.hit.u);
  hit.v = static_cast<double>(rh.hit.v);
  // Our own outward normal (b - a) x (c - a), independent of Embree's Ng sign convention.
  const Eigen::Vector3d a = corner_position(hit.prim, 0);
  const Eigen::Vector3d n = (corner_position(hit.prim, 1) - a).cross(corner_position(hit.prim, 2) - a);
  const double len = n.norm();
  hit.ng = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d(-d.normalized());
  return true;
}

Eigen::Vector3d MeshBvh::corner_position(std::uint32_t prim, int k) const {
  const std::uint32_t v = index_[std::size_t{3} * prim + static_cast<std::size_t>(k)];
  const std::size_t at = std::size_t{3} * v;
  return {static_cast<double>(vertex_[at]), static_cast<double>(vertex_[at + 1]), static_cast<double>(vertex_[at + 2])};
}

Eigen::Vector3d MeshBvh::corner_normal(std::uint32_t prim, int k) const {
  return normal_[index_[std::size_t{3} * prim + static_cast<std::size_t>(k)]].cast<double>();
}

Eigen::Vector3d MeshBvh::interpolated_normal(const MeshHit& hit) const {
  return (1.0 - hit.u - hit.v) * corner_normal(hit.prim, 0) + hit.u * corner_normal(hit.prim, 1) +
         hit.v * corner_normal(hit.prim, 2);
}

Eigen::Vector3d MeshBvh::shading_normal(const MeshHit& hit) const {
  const Eigen::Vector3d n = interpolated_normal(hit);
  const double len = n.norm();
  return len > 1e-12 ? Eigen::Vector3d(n / len) : hit.ng;
}

Eigen::Vector3d MeshBvh::shading_normal_differential(const MeshHit& hit, const Eigen::Vector3d& dp) const {
  const Eigen::Vector3d p0 = corner_position(hit.prim, 0);
  const Eigen::Vector3d e1 = corner_position(hit.prim, 1) - p0, e2 = corner_position(hit.prim, 2) - p0;
  // dp = du·e1 + dv·e2 in the least-squares sense (normal equations of the 3x2 system).
  const double a11 = e1.dot(e1), a12 = e1.dot(e2), a22 = e2.dot(e2);
  const double det = a11 * a22 - a12 * a12;
  if (!(std::abs(det) > 1e-30 * a11 * a22)) return Eigen::Vector3d::Zero();
  const double b1 = e1.dot(dp), b2 = e2.dot(dp);
  const double du = (a22 * b1 - a12 * b2) / det, dv = (a11 * b2 - a12 * b1) / det;
  const Eigen::Vector3d n = interpolated_normal(hit);
  const double len = n.norm();
  if (!(len > 1e-12)) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d n0 = corner_normal(hit.prim, 0);
  const Eigen::Vector3d dn = du * (corner_normal(hit.prim, 1) - n0) + dv * (corner_normal(hit.prim, 2) - n0);
  const Eigen::Vector3d unit = n / len;
  return (dn - unit * unit.dot(dn)) / len;  // d(n/|n|)
}

}  // namespace meltlab::render
