#pragma once
// Cameras that map object/world points (mesh units) to pixels.
//
// Pixel convention (OpenCV's): u grows to the right, v grows downwards, and integer
// coordinates are pixel CENTRES: pixel (i, j) is the square [i - 0.5, i + 0.5) x
// [j - 0.5, j + 0.5). Images are width x height, row-major, row 0 at the top.
//
// World frame: the melt meshes stand on the ground plane z = 0 with z up (the molds'
// convention); the monograph's camera looks straight down from above (§9.2).

#include <meltlab/sim/mesh.h>

#include <Eigen/Geometry>

#include <array>
#include <string>
#include <variant>

namespace YAML {
class Node;
}
namespace meltlab {
class ConfigSection;
}

namespace meltlab::render {

using Vec2d = Eigen::Vector2d;
using Vec3d = Eigen::Vector3d;

/// Orthographic view straight down the -z axis: world x -> +u, world y -> -v (so the image
/// looks like the scene seen from above with +y "up" in the picture).
///   u = (x - centre_x) * pixels_per_unit + (width - 1) / 2
///   v = -(y - centre_y) * pixels_per_unit + (height - 1) / 2
struct OrthographicTopDown {
  int width = 2048, height = 1536;   ///< the monograph's Coolpix 995 resolution
  double pixels_per_unit = 10000.0;  ///< 10 px/mm for meshes in metres
  Vec2d centre = Vec2d::Zero();      ///< world (x, y) at the image centre, mesh units

  /// pixels_per_mm with meshes in metres (mesh unit = 1 m): pixels_per_unit = 1000 * px/mm.
  static OrthographicTopDown from_pixels_per_mm(int width, int height, double pixels_per_mm, const Vec2d& centre_m);
};

/// OpenCV's pinhole model with Brown–Conrady distortion (cv::projectPoints conventions):
/// camera frame x right, y down, z forward (looking along +z_camera).
struct Pinhole {
  int width = 2048, height = 1536;
  double fx = 2000, fy = 2000, cx = 1023.5, cy = 767.5;  ///< pixels
  std::array<double, 5> distortion{0, 0, 0, 0, 0};       ///< k1 k2 p1 p2 k3
  Eigen::Isometry3d camera_from_world = Eigen::Isometry3d::Identity();

  bool distorted() const;
  /// A camera at `eye` looking at `target` with the image "up" direction closest to `up`.
  static Pinhole look_at(int width, int height, double fx, const Vec3d& eye, const Vec3d& target,
                         const Vec3d& up = Vec3d(0, 1, 0));
};

/// Equal cameras map every point to the same pixel: every field equal, bit for bit.
bool operator==(const OrthographicTopDown& a, const OrthographicTopDown& b);
bool operator==(const Pinhole& a, const Pinhole& b);

using Camera = std::variant<OrthographicTopDown, Pinhole>;

int camera_width(const Camera& c);
int camera_height(const Camera& c);

/// A rectangle of whole pixels of an image: columns [x, x + width), rows [y, y + height).
struct PixelWindow {
  int x = 0, y = 0, width = 0, height = 0;
};

/// The camera that sees `window` of `c`'s image: the same projection with pixel (0, 0) at the
/// window's corner (its pixel (u, v) is `c`'s pixel (u + x, v + y)), width x height pixels.
/// A distorted pinhole crops like any other (its distortion acts before cx, cy are added).
Camera crop(const Camera& c, const PixelWindow& window);

/// The smallest window of whole pixels that covers the image box [lo_px, hi_px] (pixel
/// coordinates, as project gives them), clamped to `c`'s image and at least 1 x 1.
PixelWindow pixel_window(const Camera& c, const Vec2d& lo_px, const Vec2d& hi_px);

/// Mesh units per pixel on the ground plane z = 0: exact for an orthographic camera; for a
/// pinhole, at the ground point seen along the optical axis (0 if the axis misses the ground).
double ground_units_per_pixel(const Camera& c);

/// A ray from the camera in the world frame.
struct CameraRay {
  Vec3d origin = Vec3d::Zero();
  Vec3d direction = Vec3d(0, 0, -1);  ///< unit length
  bool ok = true;                     ///< false where a distorted pinhole's undistortion does not converge

  /// The point `distance` (world units) along the ray.
  Vec3d at(double distance) const { return origin + distance * direction; }
};

/// Where a world point appears in the image.
struct Projection {
  Vec2d pixel = Vec2d::Zero();  ///< image point (pixel centres at integers); NaN behind a pinhole
  /// Along the viewing direction: z_camera for a pinhole, (ray start height - z) for the
  /// orthographic camera.
  double depth = 0.0;
  /// Along the ray through `pixel` from its origin: generate_ray(pixel).at(distance) is the
  /// point (world units; equal to depth for the orthographic camera).
  double distance = 0.0;
  /// False behind a pinhole camera (z_camera <= 0). Always true for the orthographic camera,
  /// which sees every height (its ray start is a rendering choice, not a position).
  bool in_front = true;
};

/// The camera's two directions, with its pose inverted once (build it per frame and query it
/// per pixel from any thread):
///   generate_ray: image point -> ray. Orthographic: origin (x, y, start_z) under image point
///     (u, v), direction -z; pinhole: origin at the eye, direction through the undistorted
///     image point.
///   project: world point -> image point (with distortion for a pinhole), the inverse.
class RayGenerator {
 public:
  /// `ortho_start_z`: the height at which orthographic rays start (above the scene).
  explicit RayGenerator(const Camera& camera, double ortho_start_z = 0.0);
  /// The ray through image point (u_px, v_px) (pixel centres at integers).
  CameraRay generate_ray(double u_px, double v_px) const;
  /// The image point of world point `p_world`, with its depth.
  Projection project(const Vec3d& p_world) const;
  const Camera& camera() const { return camera_; }

 private:
  Camera camera_;
  double ortho_start_z_ = 0.0;
  Eigen::Isometry3d world_from_camera_ = Eigen::Isometry3d::Identity();
};

/// Ideal normalized coordinates (x, y) whose OpenCV distortion (k1 k2 p1 p2 k3) is (xd, yd),
/// by Newton's method from (xd, yd). False if it does not converge to a regular solution.
bool undistort_normalized(const std::array<double, 5>& distortion, double xd, double yd, double& x_out, double& y_out);

/// Reads a camera from a config section (keys below; the caller's finish() refuses the others):
///   {type: orthographic, width: 2048, height: 1536, pixels_per_mm: 10, centre_m: [0, 0]}
///   {type: orthographic, width: W, height: H, pixels_per_unit: 1e4, centre: [x, y]}
///   {type: pinhole, width: W, height: H, fx: .., fy: .., cx: .., cy: .., distortion: [k1,k2,p1,p2,k3],
///    eye: [x,y,z], target: [x,y,z], up: [x,y,z]}       (or camera_from_world: 4x4 row-major list;
///    fov_deg: the vertical field of view instead of fx)
Camera parse_camera(const ConfigSection& section);
/// The same from a YAML node of the file `source`, refusing unknown keys.
Camera parse_camera(const YAML::Node& node, const std::string& source);

}  // namespace meltlab::render
