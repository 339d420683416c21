// Dielectric optics (material/optics.h).

#include <meltlab/render/material/optics.h>

#include <algorithm>
#include <cmath>

namespace meltlab::render {

double fresnel_dielectric(double cos_i, double eta_i, double eta_t) {
  const double c = std::clamp(cos_i, 0.0, 1.0);
  const double ratio = eta_t / eta_i;
  const double g2 = ratio * ratio + c * c - 1.0;
  if (g2 < 0.0) return 1.0;  // total internal reflection
  const double g = std::sqrt(g2);
  const double a = g - c, b = g + c;
  if (b == 0.0) return 1.0;  // grazing at ratio 1 limit (0/0): treat as full reflection
  const double num = c * b - 1.0, den = c * a + 1.0;
  return std::min(1.0, a * a / (2.0 * b * b) * (1.0 + num * num / (den * den)));
}

double fresnel_schlick(double cos_i, double eta_i, double eta_t) {
  const double r = (eta_t - eta_i) / (eta_t + eta_i);
  const double f0 = r * r;
  double c = std::clamp(cos_i, 0.0, 1.0);
  if (eta_i > eta_t) {
    const double eta = eta_i / eta_t;
    const double sin2_t = eta * eta * (1.0 - c * c);
    if (sin2_t >= 1.0) return 1.0;
    c = std::sqrt(1.0 - sin2_t);
  }
  const double m = 1.0 - c;
  const double m2 = m * m;
  return f0 + (1.0 - f0) * m2 * m2 * m;
}

double fresnel(FresnelMode mode, double cos_i, double eta_i, double eta_t) {
  return mode == FresnelMode::kFull ? fresnel_dielectric(cos_i, eta_i, eta_t) : fresnel_schlick(cos_i, eta_i, eta_t);
}

Eigen::Vector3d reflect(const Eigen::Vector3d& to_eye, const Eigen::Vector3d& n) {
  return 2.0 * n.dot(to_eye) * n - to_eye;
}

std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& incident, const Eigen::Vector3d& n, double eta) {
  const double ni = n.dot(incident);
  const double k = 1.0 - eta * eta * (1.0 - ni * ni);
  if (k < 0.0) return std::nullopt;
  return (eta * incident - (eta * ni + std::sqrt(k)) * n).normalized();
}

Eigen::Vector3d reflect_differential(const Eigen::Vector3d& to_eye, const Eigen::Vector3d& d_to_eye,
                                     const Eigen::Vector3d& n, const Eigen::Vector3d& dn) {
  return 2.0 * n.dot(to_eye) * dn + 2.0 * (dn.dot(to_eye) + n.dot(d_to_eye)) * n - d_to_eye;
}

Eigen::Vector3d refract_differential(const Eigen::Vector3d& incident, const Eigen::Vector3d& d_incident,
                                     const Eigen::Vector3d& n, const Eigen::Vector3d& dn, double eta) {
  const double c = n.dot(incident);
  const double root = std::sqrt(std::max(0.0, 1.0 - eta * eta * (1.0 - c * c)));
  const double dc = dn.dot(incident) + n.dot(d_incident);
  const double dmu = root > 0 ? (eta + eta * eta * c / root) * dc : 0.0;
  return eta * d_incident - dmu * n - (eta * c + root) * dn;
}

std::array<std::optional<Eigen::Vector3d>, 3> refract_rgb(const Eigen::Vector3d& incident, const Eigen::Vector3d& n,
                                                          const std::array<double, 3>& eta_rgb) {
  return {refract(incident, n, eta_rgb[0]), refract(incident, n, eta_rgb[1]), refract(incident, n, eta_rgb[2])};
}

std::array<double, 3> air_to_ice_eta_rgb(const std::array<double, 3>& eta_ice_rgb) {
  return {1.0 / eta_ice_rgb[0], 1.0 / eta_ice_rgb[1], 1.0 / eta_ice_rgb[2]};
}

}  // namespace meltlab::render
