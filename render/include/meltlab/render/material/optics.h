#pragma once
// Dielectric optics of the ice material (monograph §6.2-6.3, spec §7.2, Eq. 6.3-6.10).
//
// Conventions (the monograph mixes two; both are named here once):
//   * `to_eye` V points FROM the surface TO the eye (Eq. 6.3): reflect(V, N) = 2N(N·V) - V.
//   * `incident` I points FROM the eye TO the surface (GLSL/Cg refract, Eq. 6.7).
//   * N is a unit normal on the side the light arrives from (N·V >= 0, N·I <= 0).
//   * eta = eta_i / eta_t: the index of the medium the light leaves over that of the medium it
//     enters (Eq. 6.7). Air to ice is 1 / 1.31 ≈ 0.7634 (the open choice `eta_convention`).
// Directions need not be normalised on input where stated; outputs are unit vectors.

#include <Eigen/Core>

#include <array>
#include <optional>

namespace meltlab::render {

/// Relative refractive indices of ice at -7 °C (spec §7.2): the 589 nm value and the three
/// channels used for dispersion (R 656 nm, G 527 nm, B 431 nm). Shorter wavelength, larger η.
inline constexpr double kIceEta = 1.31;
inline constexpr std::array<double, 3> kIceEtaRgb{1.3079, 1.3119, 1.3169};

/// Full unpolarised Fresnel reflectance of a dielectric interface (Eq. 6.9):
///   F = (g - c)² / (2 (g + c)²) · (1 + (c (g + c) - 1)² / (c (g - c) + 1)²),
///   c = cos Θi, g = sqrt((eta_t/eta_i)² + c² - 1).
/// `cos_i` in [0, 1] is the cosine of the angle of incidence on the incident side. Returns 1
/// for total internal reflection (g² < 0, possible only when eta_t < eta_i) and at c = 0.
double fresnel_dielectric(double cos_i, double eta_i, double eta_t);

/// Schlick's approximation (Eq. 6.10): F0 + (1 - F0)(1 - cos)^5 with F0 = ((eta_t - eta_i) /
/// (eta_t + eta_i))². When eta_i > eta_t the cosine of the TRANSMITTED angle is used (the
/// usual symmetric form; with cos Θi the curve would not reach 1 at the critical angle), and
/// total internal reflection returns 1. For eta_i < eta_t it is exactly Eq. 6.10.
double fresnel_schlick(double cos_i, double eta_i, double eta_t);

enum class FresnelMode { kFull, kSchlick };  ///< open choice `fresnel_mode`
double fresnel(FresnelMode mode, double cos_i, double eta_i, double eta_t);

/// Eq. 6.3: Re = 2N(N·V) - V, V from the surface to the eye, N unit. |Re| = |V|.
Eigen::Vector3d reflect(const Eigen::Vector3d& to_eye, const Eigen::Vector3d& n);

/// Eq. 6.7 (GLSL refract): T = ηI - N(η(N·I) + sqrt(1 - η²(1 - (N·I)²))) with the
/// GLSL sign for N·I <= 0, i.e. T = ηI - (η(N·I) + sqrt(k)) N, k = 1 - η²(1 - (N·I)²).
/// `incident` and `n` unit; eta = eta_i/eta_t. Returns nullopt on total internal reflection
/// (k < 0). The result is a unit vector pointing into the far side.
std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& incident, const Eigen::Vector3d& n, double eta);

/// Ray differentials (the footprints of filtered texture lookups): the first-order change of
/// reflect(V, N) when V and N change by dV and dN,
///   dRe = 2 dN (N·V) + 2N (dN·V + N·dV) - dV.
Eigen::Vector3d reflect_differential(const Eigen::Vector3d& to_eye, const Eigen::Vector3d& d_to_eye,
                                     const Eigen::Vector3d& n, const Eigen::Vector3d& dn);
/// ... and of refract(I, N, eta) (not at total internal reflection), with c = N·I,
/// k = 1 - η²(1 - c²), dc = dN·I + N·dI:
///   dT = η dI - (η + η² c / √k) dc N - (η c + √k) dN.
Eigen::Vector3d refract_differential(const Eigen::Vector3d& incident, const Eigen::Vector3d& d_incident,
                                     const Eigen::Vector3d& n, const Eigen::Vector3d& dn, double eta);

/// Chromatic dispersion (Eq. 6.8): the three refracted directions for eta_rgb[c] (each
/// eta_i/eta_t as in refract); a channel may be nullopt (total internal reflection).
std::array<std::optional<Eigen::Vector3d>, 3> refract_rgb(const Eigen::Vector3d& incident, const Eigen::Vector3d& n,
                                                          const std::array<double, 3>& eta_rgb);

/// Air→ice eta for refract(): 1 / eta_ice per channel (≈ 0.7646, 0.7623, 0.7594 for R, G, B).
std::array<double, 3> air_to_ice_eta_rgb(const std::array<double, 3>& eta_ice_rgb = kIceEtaRgb);

}  // namespace meltlab::render
