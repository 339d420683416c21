#pragma once
// Embree BVH over the live triangles of a melting mesh, kept across cycles.
//
// Build, then query (style anchors §12): update() copies the live mesh into float arrays that
// Embree shares (rtcSetSharedGeometryBuffer, no second copy inside Embree) and commits; the
// committed BVH is then read-only and may be queried from many TBB tasks at once.
// Per cycle: when the live triangles are the same index triples as last time (only vertices
// moved), the vertex buffer is rewritten in place and the BVH is refitted
// (RTC_BUILD_QUALITY_REFIT: boxes recomputed, topology of the tree kept); when the triangles
// changed (an edge collapse, a glued pair removed), the geometry is rebuilt with a fast build.
// Smooth shading normals are area-weighted vertex normals, recomputed on every update.
// Units and frame: the mesh's object frame = world frame, mesh units. Embree works in float.

#include <meltlab/sim/mesh.h>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <vector>

namespace meltlab::render {

struct MeshHit {
  double t = 0;            ///< ray parameter (distance for a unit direction), mesh units
  std::uint32_t prim = 0;  ///< index into the BVH's triangle list
  double u = 0, v = 0;     ///< barycentrics of vertices 1 and 2
  Eigen::Vector3d ng;      ///< unit geometric normal, outward (CCW from outside)
};

enum class BvhUpdate { kNone, kRefit, kRebuild };

class MeshBvh {
 public:
  MeshBvh();
  ~MeshBvh();
  MeshBvh(const MeshBvh&) = delete;
  MeshBvh& operator=(const MeshBvh&) = delete;

  /// Loads the live triangles of `mesh` (see the header comment). Returns what was done
  /// (kNone for a mesh without live triangles: the BVH is then empty).
  template <class Real>
  BvhUpdate update(const sim::TriMesh<Real>& mesh);
  BvhUpdate update(const sim::IndexedMesh& mesh);

  /// Closest hit along o + t·d, t in (t_near, t_far). `d` need not be unit (t is then in units
  /// of |d|). Thread-safe after update().
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_near, double t_far, MeshHit& hit) const;
  /// Interpolated unit vertex normal at a hit (falls back to the geometric normal).
  Eigen::Vector3d shading_normal(const MeshHit& hit) const;
  /// The change of shading_normal(hit) when the hit point moves by `dp` in the triangle's
  /// plane (the barycentric change of dp, through the vertex normals; zero where the normal
  /// falls back to the geometric one). For the footprints of reflected and refracted rays.
  Eigen::Vector3d shading_normal_differential(const MeshHit& hit, const Eigen::Vector3d& dp) const;

  std::size_t triangle_count() const { return index_.size() / 3; }
  bool empty() const { return index_.empty(); }
  double last_update_ms() const { return last_update_ms_; }
  /// Axis-aligned bounds of the live vertices (min, max); zero if empty.
  Eigen::Vector3d lower() const { return lower_; }
  Eigen::Vector3d upper() const { return upper_; }

 private:
  BvhUpdate load(std::vector<float> positions, std::vector<std::uint32_t> index);
  Eigen::Vector3d corner_position(std::uint32_t prim, int k) const;  ///< vertex k (0..2) of triangle prim
  Eigen::Vector3d corner_normal(std::uint32_t prim, int k) const;
  Eigen::Vector3d interpolated_normal(const MeshHit& hit) const;  ///< not normalised

  struct Embree;
  std::unique_ptr<Embree> rtc_;
  std::vector<float> vertex_;         ///< 3 floats per vertex slot + 1 float of padding (SSE loads)
  std::vector<std::uint32_t> index_;  ///< 3 per live triangle
  std::vector<Eigen::Vector3f> normal_;
  Eigen::Vector3d lower_ = Eigen::Vector3d::Zero(), upper_ = Eigen::Vector3d::Zero();
  double last_update_ms_ = 0;
};

}  // namespace meltlab::render
