#pragma once
// Silhouette rasterizer: the pixels a mesh covers as seen by a camera. It is the hot path of
// comparison and fitting (a frame per photo per solver evaluation), so it is written for
// speed: back-facing triangles are skipped (the silhouette of a closed mesh is the union of
// its front faces), every triangle is filled span by span with exact edge tests at pixel
// centres (OpenCV's pixel-centre convention, top-left fill rule, so adjacent triangles
// neither overlap nor leave gaps), and buffers are reused across frames.
//
// Masks are cv::Mat CV_8UC1 with 255 inside and 0 outside; coverage images are CV_32FC1 in
// [0, 1] (fraction of sub-samples inside).

#include <meltlab/render/camera.h>
#include <meltlab/sim/mesh.h>

#include <opencv2/core.hpp>

#include <memory>

namespace meltlab::render {

struct SilhouetteOptions {
  int supersample = 1;       ///< k: k x k samples per pixel (1 = binary mask from pixel centres)
  bool cull_backfaces = true;  ///< closed, outward meshes only; false renders every triangle
};

/// Binary mask (supersample = 1) of the live triangles of `mesh` seen by `camera`.
template <class Real>
cv::Mat silhouette_mask(const sim::TriMesh<Real>& mesh, const Camera& camera, const SilhouetteOptions& options = {});
cv::Mat silhouette_mask(const sim::IndexedMesh& mesh, const Camera& camera, const SilhouetteOptions& options = {});

/// Coverage in [0, 1] with options.supersample^2 samples per pixel.
template <class Real>
cv::Mat silhouette_coverage(const sim::TriMesh<Real>& mesh, const Camera& camera, const SilhouetteOptions& options);

/// Stateful renderer for repeated frames of one camera: keeps its projection buffers and,
/// for a distorted pinhole camera, the undistortion maps.
class SilhouetteRenderer {
 public:
  explicit SilhouetteRenderer(Camera camera, SilhouetteOptions options = {});
  ~SilhouetteRenderer();
  SilhouetteRenderer(SilhouetteRenderer&&) noexcept;
  SilhouetteRenderer& operator=(SilhouetteRenderer&&) noexcept;

  /// Renders into `out` (reallocated only if its size/type differ): CV_8UC1 0/255 if
  /// supersample == 1, else CV_32FC1 coverage.
  template <class Real>
  void render(const sim::TriMesh<Real>& mesh, cv::Mat& out);

  const Camera& camera() const;
  const SilhouetteOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meltlab::render
