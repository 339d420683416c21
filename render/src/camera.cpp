// Cameras: orthographic top-down and OpenCV pinhole, their projection, YAML parsing and
// JSON description (see camera.h).

#include <meltlab/render/camera.h>
#include <meltlab/core/config.h>
#include <meltlab/core/error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace meltlab::render {

OrthographicTopDown OrthographicTopDown::from_pixels_per_mm(int width, int height, double pixels_per_mm,
                                                            const Vec2d& centre_m) {
  OrthographicTopDown c;
  c.width = width;
  c.height = height;
  c.pixels_per_unit = 1000.0 * pixels_per_mm;
  c.centre = centre_m;
  return c;
}

bool Pinhole::distorted() const {
  for (double d : distortion)
    if (d != 0.0) return true;
  return false;
}

Pinhole Pinhole::look_at(int width, int height, double fx, const Vec3d& eye, const Vec3d& target, const Vec3d& up) {
  const Vec3d forward = target - eye;
  if (!eye.allFinite() || !target.allFinite() || !up.allFinite() || forward.norm() == 0.0)
    throw InputError("Pinhole::look_at: eye and target must be finite and distinct");
  const Vec3d z = forward.normalized();
  // Image "up" is -y_camera: take the component of `up` orthogonal to the view direction. If
  // `up` is (nearly) parallel to it, fall back to the world axis least aligned with the view.
  Vec3d u = up - up.dot(z) * z;
  if (u.norm() <= 1e-9 * std::max(1.0, up.norm())) {
    Eigen::Index axis = 0;
    z.cwiseAbs().minCoeff(&axis);
    const Vec3d a = Vec3d::Unit(axis);
    u = a - a.dot(z) * z;
  }
  const Vec3d y = -u.normalized();
  const Vec3d x = y.cross(z);  // right-handed: x × y = z
  Pinhole p;
  p.width = width;
  p.height = height;
  p.fx = fx;
  p.fy = fx;
  p.cx = 0.5 * (width - 1);
  p.cy = 0.5 * (height - 1);
  Eigen::Matrix3d R;
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  p.camera_from_world = Eigen::Isometry3d::Identity();
  p.camera_from_world.linear() = R;
  p.camera_from_world.translation() = -R * eye;
  return p;
}

int camera_width(const Camera& c) {
  return std::visit([](const auto& cam) { return cam.width; }, c);
}
int camera_height(const Camera& c) {
  return std::visit([](const auto& cam) { return cam.height; }, c);
}

Camera crop(const Camera& c, const PixelWindow& window) {
  if (const auto* o = std::get_if<OrthographicTopDown>(&c)) {
    // The window's centre pixel, in the full image, is where the cropped camera's centre is.
    OrthographicTopDown cropped = *o;
    cropped.width = window.width;
    cropped.height = window.height;
    cropped.centre.x() =
        o->centre.x() + ((window.width - 1) / 2.0 - (o->width - 1) / 2.0 + window.x) / o->pixels_per_unit;
    cropped.centre.y() =
        o->centre.y() - ((window.height - 1) / 2.0 - (o->height - 1) / 2.0 + window.y) / o->pixels_per_unit;
    return cropped;
  }
  Pinhole cropped = std::get<Pinhole>(c);
  cropped.width = window.width;
  cropped.height = window.height;
  cropped.cx -= window.x;
  cropped.cy -= window.y;
  return cropped;
}

PixelWindow pixel_window(const Camera& c, const Vec2d& lo_px, const Vec2d& hi_px) {
  const int W = camera_width(c), H = camera_height(c);
  const int x0 = std::clamp(static_cast<int>(std::floor(lo_px.x())), 0, W - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(lo_px.y())), 0, H - 1);
  const int x1 = std::clamp(static_cast<int>(std::ceil(hi_px.x())), x0 + 1, W);
  const int y1 = std::clamp(static_cast<int>(std::ceil(hi_px.y())), y0 + 1, H);
  return PixelWindow{x0, y0, x1 - x0, y1 - y0};
}

double ground_units_per_pixel(const Camera& c) {
  if (const auto* o = std::get_if<OrthographicTopDown>(&c)) return 1.0 / o->pixels_per_unit;
  const auto& p = std::get<Pinhole>(c);
  // Ray through the principal point, in world coordinates.
  const Eigen::Isometry3d world_from_camera = p.camera_from_world.inverse();
  const Vec3d origin = world_from_camera.translation();
  const Vec3d dir = world_from_camera.linear() * Vec3d(0, 0, 1);
  if (std::abs(dir.z()) < 1e-12) return 0.0;
  const double t = -origin.z() / dir.z();
  if (t <= 0) return 0.0;
  return t / p.fx;  // depth along the optical axis ≈ t (the axis is the ray)
}

RayGenerator::RayGenerator(const Camera& camera, double ortho_start_z)
    : camera_(camera), ortho_start_z_(ortho_start_z) {
  if (const auto* p = std::get_if<Pinhole>(&camera_)) world_from_camera_ = p->camera_from_world.inverse();
}

CameraRay RayGenerator::generate_ray(double u_px, double v_px) const {
  CameraRay r;
  if (const auto* ortho = std::get_if<OrthographicTopDown>(&camera_)) {
    const double x = ortho->centre.x() + (u_px - 0.5 * (ortho->width - 1)) / ortho->pixels_per_unit;
    const double y = ortho->centre.y() - (v_px - 0.5 * (ortho->height - 1)) / ortho->pixels_per_unit;
    r.origin = Vec3d(x, y, ortho_start_z_);
    r.direction = Vec3d(0, 0, -1);
    return r;
  }
  const auto& pin = std::get<Pinhole>(camera_);
  double x = (u_px - pin.cx) / pin.fx, y = (v_px - pin.cy) / pin.fy;
  if (pin.distorted()) {
    double ux = x, uy = y;
    r.ok = undistort_normalized(pin.distortion, x, y, ux, uy);
    x = ux;
    y = uy;
  }
  r.origin = world_from_camera_.translation();
  r.direction = (world_from_camera_.linear() * Vec3d(x, y, 1.0)).normalized();
  return r;
}

Projection RayGenerator::project(const Vec3d& p_world) const {
  Projection out;
  if (const auto* o = std::get_if<OrthographicTopDown>(&camera_)) {
    const double u = (p_world.x() - o->centre.x()) * o->pixels_per_unit + 0.5 * (o->width - 1);
    const double v = -(p_world.y() - o->centre.y()) * o->pixels_per_unit + 0.5 * (o->height - 1);
    out.pixel = Vec2d(u, v);
    out.depth = out.distance = ortho_start_z_ - p_world.z();
    return out;
  }
  const auto& p = std::get<Pinhole>(camera_);
  const Vec3d q = p.camera_from_world * p_world;
  out.depth = q.z();
  out.distance = q.norm();
  if (!(q.z() > 0.0)) {
    out.pixel = Vec2d(std::nan(""), std::nan(""));
    out.in_front = false;
    return out;
  }
  const double x = q.x() / q.z(), y = q.y() / q.z();
  const double k1 = p.distortion[0], k2 = p.distortion[1], p1 = p.distortion[2], p2 = p.distortion[3],
               k3 = p.distortion[4];
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  out.pixel = Vec2d(p.fx * xd + p.cx, p.fy * yd + p.cy);
  return out;
}

// ---- YAML -----------------------------------------------------------------------------

namespace {

// Image sizes: at least a pixel, at most what any camera we model has (and what fits an int
// product of width and height).
constexpr int kMaxImageSide = 65536;

// A list of exactly 3 numbers; as a camera's lists, it may be written as rows ([[x, y], z]).
Vec3d numbers3(const ConfigSection& c, const std::string& key) {
  const auto v = c.require_numbers(key, 3, 3);
  return {v[0], v[1], v[2]};
}

Camera parse_orthographic(const ConfigSection& c) {
  OrthographicTopDown o;
  o.width = c.require_in_range<int>("width", 1, kMaxImageSide);
  o.height = c.require_in_range<int>("height", 1, kMaxImageSide);
  if (c.has("pixels_per_mm") == c.has("pixels_per_unit"))
    c.fail("give exactly one of 'pixels_per_mm' and 'pixels_per_unit'");
  if (c.has("centre_m") && c.has("centre")) c.fail("give at most one of 'centre_m' and 'centre'");
  o.pixels_per_unit =
      c.has("pixels_per_mm") ? 1000.0 * c.require_positive("pixels_per_mm") : c.require_positive("pixels_per_unit");
  for (const char* key : {"centre_m", "centre"}) {
    if (!c.has(key)) continue;
    const auto v = c.require_numbers(key, 2, 2);
    o.centre = Vec2d(v[0], v[1]);
  }
  return o;
}

Camera parse_pinhole(const ConfigSection& c) {
  const int width = c.require_in_range<int>("width", 1, kMaxImageSide);
  const int height = c.require_in_range<int>("height", 1, kMaxImageSide);
  // The focal length in pixels, or the vertical field of view it gives (fx = (height / 2) / tan(fov / 2)).
  if (c.has("fx") == c.has("fov_deg")) c.fail("give exactly one of 'fx' and 'fov_deg'");
  const double fx =
      c.has("fx") ? c.require_positive("fx")
                  : 0.5 * height /
                        std::tan(0.5 * c.get_in_range<double>("fov_deg", 45.0, 1e-3, 179.0) * std::numbers::pi / 180.0);
  Pinhole p;
  const bool has_pose = c.has("eye") || c.has("target") || c.has("up");
  if (c.has("camera_from_world")) {
    if (has_pose) c.fail("give either 'camera_from_world' or 'eye'/'target'/'up', not both");
    const auto m = c.require_numbers("camera_from_world", 16, 16);
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r)
      for (int col = 0; col < 4; ++col) M(r, col) = m[static_cast<std::size_t>(4 * r + col)];
    const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
    // Tolerance: a rotation written with ~10 significant digits is orthonormal to ~1e-9.
    const double ortho_err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (ortho_err > 1e-6 || R.determinant() <= 0.0 || M(3, 0) != 0.0 || M(3, 1) != 0.0 || M(3, 2) != 0.0 ||
        M(3, 3) != 1.0)
      c.fail_at("camera_from_world",
                "'camera_from_world' must be a rigid transform (rotation + translation, last row 0 0 0 1)");
    p.camera_from_world.matrix() = M;
    p.width = width;
    p.height = height;
    p.fx = p.fy = fx;
    p.cx = 0.5 * (width - 1);
    p.cy = 0.5 * (height - 1);
  } else {
    if (!c.has("eye")) c.fail("missing key 'eye' (or 'camera_from_world')");
    const Vec3d eye = numbers3(c, "eye");
    const Vec3d target = numbers3(c, "target");
    const Vec3d up = c.has("up") ? numbers3(c, "up") : Vec3d(0, 1, 0);
    if (eye == target) c.fail("'eye' and 'target' coincide");
    p = Pinhole::look_at(width, height, fx, eye, target, up);
  }
  if (c.has("fy")) p.fy = c.require_positive("fy");
  p.cx = c.get<double>("cx", p.cx);
  p.cy = c.get<double>("cy", p.cy);
  if (c.has("distortion")) {
    const auto d = c.require_numbers("distortion", 4, 5);  // OpenCV accepts k1 k2 p1 p2 [k3]
    for (std::size_t i = 0; i < 5; ++i) p.distortion[i] = i < d.size() ? d[i] : 0.0;
  }
  return p;
}

}  // namespace

Camera parse_camera(const ConfigSection& c) {
  if (!c.has("type")) c.fail("missing key 'type' (orthographic or pinhole)");
  const std::string type = c.get_choice("type", "", {"orthographic", "pinhole"});
  return type == "orthographic" ? parse_orthographic(c) : parse_pinhole(c);
}

Camera parse_camera(const YAML::Node& node, const std::string& source) {
  const ConfigSection c(node, source, "camera");
  const Camera camera = parse_camera(c);
  c.finish();
  return camera;
}

bool operator==(const OrthographicTopDown& a, const OrthographicTopDown& b) {
  return a.width == b.width && a.height == b.height && a.pixels_per_unit == b.pixels_per_unit && a.centre == b.centre;
}

bool operator==(const Pinhole& a, const Pinhole& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy &&
         a.distortion == b.distortion && a.camera_from_world.matrix() == b.camera_from_world.matrix();
}

bool undistort_normalized(const std::array<double, 5>& d, double xd, double yd, double& x_out, double& y_out) {
  const double k1 = d[0], k2 = d[1], p1 = d[2], p2 = d[3], k3 = d[4];
  double x = xd, y = yd;
  for (int it = 0; it < 50; ++it) {
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);
    const double fx = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - xd;
    const double fy = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - yd;
    const double j11 = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
    const double j12 = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    const double j22 = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
    const double det = j11 * j22 - j12 * j12;  // the Jacobian is symmetric
    if (!(det > 0.0) || !(radial > 0.0)) return false;
    // Converged: residual below 1e-13 in normalized units (~1e-10 px for f ~ 1000 px).
    if (std::abs(fx) + std::abs(fy) < 1e-13) {
      x_out = x;
      y_out = y;
      return true;
    }
    x -= (j22 * fx - j12 * fy) / det;
    y -= (j11 * fy - j12 * fx) / det;
    if (!std::isfinite(x) || !std::isfinite(y)) return false;
  }
  return false;
}

}  // namespace meltlab::render
