#include <meltlab/core/error.h>
#include <meltlab/verify/metrics.h>
#include <meltlab/verify/registration.h>

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>
#include <limits>
#include <numbers>

namespace meltlab::verify {

Vec2d Similarity2D::apply(const Vec2d& p) const {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return scale * Vec2d(c * p.x() - s * p.y(), s * p.x() + c * p.y()) + translation;
}

Similarity2D Similarity2D::inverse() const {
  Similarity2D inv;
  inv.scale = 1.0 / scale;
  inv.angle_rad = -angle_rad;
  inv.translation = Vec2d::Zero();
  inv.translation = -inv.apply(translation);  // -s^-1 R^-1 t
  return inv;
}

cv::Mat Similarity2D::matrix() const {
  const double c = scale * std::cos(angle_rad), s = scale * std::sin(angle_rad);
  cv::Mat m = (cv::Mat_<double>(2, 3) << c, -s, translation.x(), s, c, translation.y());
  return m;
}

Similarity2D compose(const Similarity2D& a, const Similarity2D& b) {
  Similarity2D r;
  r.scale = a.scale * b.scale;
  r.angle_rad = a.angle_rad + b.angle_rad;
  r.translation = a.apply(b.translation);
  return r;
}

cv::Mat warp_mask(const cv::Mat& mask, const Similarity2D& t, cv::Size size) {
  cv::Mat out;
  cv::warpAffine(mask, out, t.matrix(), size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, cv::Scalar(0));
  return out;
}

Region transform_region(const Region& region, const Similarity2D& t) {
  Region out = region;  // a similarity with scale > 0 keeps every loop's orientation
  for (auto& poly : out) {
    for (auto& p : poly.outer) p = t.apply(p);
    for (auto& h : poly.holes)
      for (auto& p : h) p = t.apply(p);
  }
  return out;
}

namespace {

struct Moments {
  double area = 0;
  Vec2d centroid = Vec2d::Zero();
  double orientation = 0;  // principal axis angle, radians
  double elongation = 0;   // 1 - minor/major eigenvalue ratio
};

Moments mask_moments(const cv::Mat& mask) {
  const cv::Moments m = cv::moments(mask, true);
  Moments out;
  out.area = m.m00;
  if (m.m00 <= 0) return out;
  out.centroid = Vec2d(m.m10 / m.m00, m.m01 / m.m00);
  const double a = m.mu20 / m.m00, b = m.mu11 / m.m00, c = m.mu02 / m.m00;
  out.orientation = 0.5 * std::atan2(2 * b, a - c);
  const double common = std::sqrt(4 * b * b + (a - c) * (a - c));
  const double l1 = 0.5 * (a + c + common), l2 = 0.5 * (a + c - common);
  out.elongation = l1 > 0 ? 1.0 - l2 / l1 : 0.0;
  return out;
}

double p_of(const cv::Mat& photo, const cv::Mat& render, const Similarity2D& t) {
  return compare_masks(photo, warp_mask(render, t, photo.size())).P;
}

// Boundary points of a mask (pixel centres of boundary pixels), at most `max_points`.
std::vector<Vec2d> boundary_points(const cv::Mat& mask, std::size_t max_points) {
  std::vector<std::vector<cv::Point>> contours;
  cv::Mat copy = mask.clone();
  cv::findContours(copy, contours, cv::RETR_LIST, cv::CHAIN_APPROX_NONE);
  std::size_t total = 0;
  for (const auto& c : contours) total += c.size();
  const std::size_t step = std::max<std::size_t>(1, total / std::max<std::size_t>(1, max_points));
  std::vector<Vec2d> pts;
  std::size_t k = 0;
  for (const auto& c : contours)
    for (const auto& p : c)
      if (k++ % step == 0) pts.emplace_back(p.x, p.y);
  return pts;
}

// Nearest-neighbour queries on a fixed point set through a uniform grid.
class PointGrid {
 public:
  PointGrid(const std::vector<Vec2d>& pts, double cell) : pts_(pts), cell_(cell) {
    lo_ = Vec2d(std::numeric_limits<double>::max(), std::numeric_limits<double>::max());
    Vec2d hi = -lo_;
    for (const auto& p : pts) {
      lo_ = lo_.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    nx_ = std::max(1, static_cast<int>((hi.x() - lo_.x()) / cell_) + 1);
    ny_ = std::max(1, static_cast<int>((hi.y() - lo_.y()) / cell_) + 1);
    start_.assign(static_cast<std::size_t>(nx_ * ny_ + 1), 0);
    for (const auto& p : pts) ++start_[static_cast<std::size_t>(index(p)) + 1];
    for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
    order_.resize(pts.size());
    std::vector<int> cursor(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < pts.size(); ++i)
      order_[static_cast<std::size_t>(cursor[static_cast<std::size_t>(index(pts[i]))]++)] = static_cast<int>(i);
  }
  // Index of the nearest point to q.
  int nearest(const Vec2d& q) const {
    const int cx = std::clamp(static_cast<int>((q.x() - lo_.x()) / cell_), 0, nx_ - 1);
    const int cy = std::clamp(static_cast<int>((q.y() - lo_.y()) / cell_), 0, ny_ - 1);
    int best = -1;
    double best_d2 = std::numeric_limits<double>::max();
    for (int r = 0; r < std::max(nx_, ny_); ++r) {
      for (int y = cy - r; y <= cy + r; ++y)
        for (int x = cx - r; x <= cx + r; ++x) {
          if (x < 0 || y < 0 || x >= nx_ || y >= ny_) continue;
          if (std::max(std::abs(x - cx), std::abs(y - cy)) != r) continue;
          const auto c = static_cast<std::size_t>(y * nx_ + x);
          for (int i = start_[c]; i < start_[c + 1]; ++i) {
            const int k = order_[static_cast<std::size_t>(i)];
            const double d2 = (pts_[static_cast<std::size_t>(k)] - q).squaredNorm();
            if (d2 < best_d2) best_d2 = d2, best = k;
          }
        }
      // Every point in rings beyond r is at least r * cell away.
      if (best >= 0 && std::sqrt(best_d2) <= r * cell_) break;
    }
    return best;
  }

 private:
  int index(const Vec2d& p) const {
    const int x = std::clamp(static_cast<int>((p.x() - lo_.x()) / cell_), 0, nx_ - 1);
    const int y = std::clamp(static_cast<int>((p.y() - lo_.y()) / cell_), 0, ny_ - 1);
    return y * nx_ + x;
  }
  const std::vector<Vec2d>& pts_;
  double cell_;
  Vec2d lo_;
  int nx_ = 1, ny_ = 1;
  std::vector<int> start_, order_;
};

/// Least-squares similarity q ≈ s R(θ) p + t between corresponding points, in closed form
/// (Umeyama's solution specialised to 2-D: with centred points, θ = atan2(Σ p×q, Σ p·q) and
/// s = |(Σ p·q, Σ p×q)| / Σ|p|²; without rotation θ = 0 and s = Σ p·q / Σ|p|²).
Similarity2D fit_similarity(const std::vector<Vec2d>& p, const std::vector<Vec2d>& q, bool allow_scale,
                            bool allow_rotation) {
  const double n = static_cast<double>(p.size());
  Vec2d pm = Vec2d::Zero(), qm = Vec2d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) pm += p[i], qm += q[i];
  pm /= n;
  qm /= n;
  double dot = 0, cross = 0, pp = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec2d a = p[i] - pm, b = q[i] - qm;
    dot += a.dot(b);
    cross += a.x() * b.y() - a.y() * b.x();
    pp += a.squaredNorm();
  }
  Similarity2D t;
  t.angle_rad = allow_rotation ? std::atan2(cross, dot) : 0.0;
  if (allow_scale && pp > 0) t.scale = allow_rotation ? std::hypot(dot, cross) / pp : std::max(dot / pp, 1e-9);
  t.translation = Vec2d::Zero();
  t.translation = qm - t.apply(pm);
  return t;
}

}  // namespace

namespace {

/// Scale from the areas, rotation from the principal axes (both senses) or none, centroids
/// aligned: the candidate with the lowest P; `best_p` receives it.
Similarity2D moment_estimate(const cv::Mat& photo, const cv::Mat& render, const Moments& mp, const Moments& mr,
                             const RegistrationOptions& options, double& best_p) {
  const double scale = options.allow_scale ? std::sqrt(mp.area / mr.area) : 1.0;
  std::vector<double> angles = {0.0};
  // The principal axis is only meaningful for elongated shapes; it is ambiguous by 180°.
  if (options.allow_rotation && mp.elongation > 0.05 && mr.elongation > 0.05) {
    const double d = mp.orientation - mr.orientation;
    angles = {d, d + std::numbers::pi};
  }
  Similarity2D best;
  best_p = std::numeric_limits<double>::infinity();
  for (double a : angles) {
    Similarity2D t;
    t.scale = scale;
    t.angle_rad = std::remainder(a, 2 * std::numbers::pi);
    t.translation = Vec2d::Zero();
    t.translation = mp.centroid - t.apply(mr.centroid);
    const double p = p_of(photo, render, t);
    if (p < best_p) best_p = p, best = t;
  }
  // The unrotated candidate too (nearly aligned inputs should not be turned by noise).
  {
    Similarity2D t;
    t.scale = scale;
    t.translation = mp.centroid - scale * mr.centroid;
    const double p = p_of(photo, render, t);
    if (p <= best_p) best_p = p, best = t;
  }
  return best;
}

/// Trimmed ICP of the rendered boundary onto the photo's from `best`; replaces
/// result.render_to_photo (and best_p) if it lowers P.
void refine_icp(const cv::Mat& photo, const cv::Mat& render, const Similarity2D& best,
                const RegistrationOptions& options, RegistrationResult& result, double& best_p) {
  const std::vector<Vec2d> target = boundary_points(photo, 4000);
  const std::vector<Vec2d> source = boundary_points(render, 4000);
  PointGrid grid(target, 8.0);
  Similarity2D t = best;
  for (int it = 0; it < options.max_iterations; ++it) {
    std::vector<Vec2d> dst(source.size());
    std::vector<double> dist(source.size());
    for (std::size_t i = 0; i < source.size(); ++i) {
      const Vec2d p = t.apply(source[i]);
      dst[i] = target[static_cast<std::size_t>(grid.nearest(p))];
      dist[i] = (p - dst[i]).norm();
    }
    // Trim the worst 10% of correspondences (parts present in one contour only).
    std::vector<double> sorted = dist;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * 9 / 10),
                     sorted.end());
    const double cut = sorted[sorted.size() * 9 / 10];
    std::vector<Vec2d> s2, d2;
    s2.reserve(source.size());
    d2.reserve(source.size());
    for (std::size_t i = 0; i < dist.size(); ++i) {
      if (dist[i] > cut) continue;
      s2.push_back(source[i]);
      d2.push_back(dst[i]);
    }
    const Similarity2D next = fit_similarity(s2, d2, options.allow_scale, options.allow_rotation);
    double move = 0;
    for (const auto& p : source) move = std::max(move, (next.apply(p) - t.apply(p)).norm());
    t = next;
    result.iterations = it + 1;
    if (move < options.tolerance_px) {
      result.converged = true;
      break;
    }
  }
  const double p = p_of(photo, render, t);
  if (p <= best_p) {
    best_p = p;
    result.render_to_photo = t;
  }
}

/// ECC on blurred masks from `best`; replaces result.render_to_photo (and best_p) if it
/// lowers P, keeps the moment estimate if ECC fails.
void refine_ecc(const cv::Mat& photo, const cv::Mat& render, const Similarity2D& best,
                const RegistrationOptions& options, RegistrationResult& result, double& best_p) {
  // ECC estimates a Euclidean warp between blurred masks; the moment scale is applied first.
  Similarity2D scale_only;
  scale_only.scale = best.scale;
  const Vec2d c = Vec2d(photo.cols / 2.0, photo.rows / 2.0);
  scale_only.translation = c - best.scale * c;
  const cv::Mat scaled = warp_mask(render, scale_only, photo.size());
  cv::Mat a, b;
  photo.convertTo(a, CV_32F, 1.0 / 255);
  scaled.convertTo(b, CV_32F, 1.0 / 255);
  const int k = 2 * static_cast<int>(std::ceil(3 * options.ecc_blur_sigma_px)) + 1;
  cv::GaussianBlur(a, a, cv::Size(k, k), options.ecc_blur_sigma_px);
  cv::GaussianBlur(b, b, cv::Size(k, k), options.ecc_blur_sigma_px);
  // Initial guess from the moments: the remaining rotation and translation.
  Similarity2D rest = compose(best, scale_only.inverse());
  cv::Mat warp = (cv::Mat_<float>(2, 3) << static_cast<float>(std::cos(rest.angle_rad)),
                  static_cast<float>(-std::sin(rest.angle_rad)), static_cast<float>(rest.translation.x()),
                  static_cast<float>(std::sin(rest.angle_rad)), static_cast<float>(std::cos(rest.angle_rad)),
                  static_cast<float>(rest.translation.y()));
  // findTransformECC maps template (photo) coordinates into the input image: invert.
  cv::Mat inv;
  cv::invertAffineTransform(warp, inv);
  try {
    cv::findTransformECC(
        a, b, inv, cv::MOTION_EUCLIDEAN,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, options.max_iterations, 1e-7), cv::noArray(),
        1);
    cv::invertAffineTransform(inv, warp);
    Similarity2D e;
    e.angle_rad = std::atan2(warp.at<float>(1, 0), warp.at<float>(0, 0));
    e.translation = Vec2d(warp.at<float>(0, 2), warp.at<float>(1, 2));
    const Similarity2D t = compose(e, scale_only);
    result.converged = true;
    const double p = p_of(photo, render, t);
    if (p <= best_p) {
      best_p = p;
      result.render_to_photo = t;
    }
  } catch (const cv::Exception&) {
    result.converged = false;  // keep the moment estimate
  }
}

}  // namespace

RegistrationResult register_masks(const cv::Mat& photo, const cv::Mat& render, const RegistrationOptions& options) {
  if (photo.empty() || render.empty() || photo.size() != render.size() || photo.type() != CV_8UC1 ||
      render.type() != CV_8UC1)
    throw std::invalid_argument("register_masks: masks must be non-empty CV_8UC1 images of the same size");
  const Moments mp = mask_moments(photo), mr = mask_moments(render);
  if (mp.area <= 0) throw InputError("registration: the photo mask is empty");
  if (mr.area <= 0) throw InputError("registration: the rendered mask is empty");
  RegistrationResult result;
  result.P_before = p_of(photo, render, Similarity2D::identity());
  double best_p = std::numeric_limits<double>::infinity();
  const Similarity2D best = moment_estimate(photo, render, mp, mr, options, best_p);
  result.render_to_photo = best;
  result.method = "moments";
  if (options.refine == RegistrationOptions::Refine::kIcp) {
    result.method = "moments+icp";
    refine_icp(photo, render, best, options, result, best_p);
  } else if (options.refine == RegistrationOptions::Refine::kEcc) {
    result.method = "moments+ecc";
    refine_ecc(photo, render, best, options, result, best_p);
  }
  result.P_after = best_p;
  return result;
}

}  // namespace meltlab::verify
