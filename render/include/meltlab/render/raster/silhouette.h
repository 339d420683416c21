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
//
// Exactness: projected vertices are snapped to 1/256 of a (sub-)pixel, then every edge test is
// exact integer arithmetic, so a pixel centre on an edge shared by two triangles goes to exactly
// one of them (left/top edges inclusive, right/bottom exclusive) and the result depends only on
// the covered region, not on how it is triangulated.
// Sub-samples: pixel (i, j) with k x k sub-samples at (i - 0.5 + (s + 0.5) / k, j - 0.5 + (t + 0.5) / k).
// Clipping: triangles reaching beyond a guard band of 2^19 (sub-)pixels, or (pinhole) behind the
// camera, are clipped in homogeneous coordinates against the guard band and the plane
// z_camera = 1e-9 mesh units, so the visible part in front of the camera is drawn exactly as
// projected and nothing behind it is drawn; only such clipped triangles can differ from their
// neighbours by rounding, and only outside the image.
// Lens distortion (pinhole with distortion): the mesh is rendered into an ideal (undistorted)
// image whose extent covers every output pixel's undistorted position, then resampled: each
// output pixel centre is undistorted once per renderer (Newton's method on OpenCV's model, the
// inverse of cv::projectPoints' distortion) and looks up the nearest ideal pixel (binary mask)
// or interpolates bilinearly (coverage). The boundary is therefore exact to half an ideal pixel.
// Output pixels whose undistortion does not converge (beyond the model's fold) stay 0.

#include <meltlab/render/camera.h>
#include <meltlab/sim/mesh.h>

#include <opencv2/core.hpp>

#include <memory>

namespace meltlab::render {

struct SilhouetteOptions {
  int supersample = 1;         ///< k: k x k samples per pixel (1 = binary mask from pixel centres)
  bool cull_backfaces = true;  ///< closed, outward meshes only; false renders every triangle
  bool parallel = true;        ///< row bands in parallel (TBB); the result is identical either way
};

/// Binary mask of the live triangles of `mesh` seen by `camera` (options.supersample is ignored:
/// the mask samples pixel centres).
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
  /// The same for a compact indexed mesh (every triangle live).
  void render(const sim::IndexedMesh& mesh, cv::Mat& out);

  const Camera& camera() const;
  const SilhouetteOptions& options() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meltlab::render
