#pragma once
// Fitting the melt model's coefficients to observations with Ceres (issue 5).
//
// P (Eq. 8.1) counts pixels and is piecewise constant in the parameters, so it is not what
// the solver sees. Per photo the residuals are
//   - the signed distances of N_p points spread along the photo's sub-pixel contour to the
//     rendered contour (negative inside the render),
//   - the signed distances of N_r points spread along the rendered contour to the photo's
//     contour (negative inside the photo),
//   - the area difference divided by the photo contour's perimeter (a mean boundary offset),
// all in photo pixels. The rendered contour is the 1/2 level of a k x k supersampled
// coverage image (marching squares), so it moves continuously with the mesh down to about
// 1/k² px; the distances are exact point-to-segment distances. Each photo is one residual
// block with a robust (Huber) loss, so a bad photo is down-weighted, not fitted.
// A volume/mass time series adds residuals (V_model(t) - V_obs(t)) / V_obs(0) * weight.
//
// The simulation depends on every parameter, so all residual blocks of one parameter vector
// come from one simulation; evaluations are cached by parameter vector and shared by the
// blocks. Derivatives are central differences with a fixed step in each parameter's
// characteristic scale (FitParameter::scale x step_fraction), chosen to move the contours by
// well over the 1/k² px quantisation of the rendered contour (see fit.cpp and the tests).
//
// Parameters (physical units; bounds; any can be fixed; registered with their roles,
// defaults, bounds and scales in fit_parameters.h):
//   kg, kl.<yaml path> (model parameters, passed to FitModel::start)
//   cycles_per_photo   photo k shows cycle first_cycle + k * K (fractional cycles blend the
//                      residuals of the two neighbouring cycles, so K is fitted smoothly)
//   reg.tx_px, reg.ty_px, reg.angle_deg, reg.scale   render -> photo similarity, rotation
//                      and scale about the first photo's object centroid (the pivot), so
//                      that the four are nearly uncorrelated:
//                      p_photo = pivot + scale R(angle) (p_render - pivot) + (tx, ty)

#include <meltlab/verify/compare.h>
#include <meltlab/verify/fit_parameters.h>
#include <meltlab/verify/observations.h>

#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::verify {

struct FitParameter {
  std::string name;
  double initial = 0;
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  double scale = 1;  ///< characteristic size: the solver works in units of `scale`
  bool fixed = false;
};

/// The simulation side of a fit: a mesh sequence for given model-parameter values (every
/// parameter for which is_model_parameter holds: melt settings and kl field numbers). Any
/// model fits behind it — the melt simulator in `meltlab fit`, an analytic shrinking disc in
/// tests/verify/fit_test.cpp.
class FitModel {
 public:
  virtual ~FitModel() = default;
  virtual std::unique_ptr<sim::MeshSequence> start(const std::map<std::string, double>& model_values) = 0;
};

struct FitOptions {
  int photo_samples = 48;       ///< N_p points per photo contour
  int render_samples = 48;      ///< N_r points per rendered contour
  int supersample = 4;          ///< k of the rendered coverage
  double step_fraction = 0.25;  ///< central-difference step = step_fraction * scale
  double huber_px = 2.0;        ///< per-photo robust loss: RMS residual above which a photo is down-weighted
  double margin_px = 40;        ///< rendered window around the photo's object
  int max_iterations = 40;
  double first_cycle = 0;
  std::vector<double> kg_scan;                  ///< factors of kg's initial value tried first (empty = no scan)
  double volume_weight = 0;                     ///< weight of the volume residuals (0 = not used)
  std::vector<int> frames;                      ///< frames (0-based) to fit; empty = all readable
  bool initial_registration = true;             ///< start free reg.* parameters from register_masks on the first photo
  std::function<void(const std::string&)> log;  ///< one line per event (scan, iteration)
};

struct FitEstimate {
  std::string name;
  double value = 0;
  double initial = 0;
  std::optional<double> standard_error;
  bool fixed = false;
  bool at_bound = false;
};

struct FitResult {
  std::vector<FitEstimate> estimates;
  std::vector<std::string> free_names;
  std::vector<std::vector<double>> correlation;  ///< free x free, empty if not computable
  double initial_cost = 0, final_cost = 0;
  int iterations = 0;
  int simulations = 0;  ///< model evaluations (each a full simulation + renders)
  double time_s = 0;
  bool converged = false;
  std::string message;                             ///< Ceres' termination message
  std::vector<std::pair<double, double>> kg_scan;  ///< (kg, cost) of the coarse scan
  std::vector<int> frames_used;
  std::vector<std::string> frames_refused;  ///< "frame N: reason"
  std::vector<double> frame_rms_px;         ///< residual RMS per used frame at the optimum
  double residual_sigma_px = 0;             ///< sqrt(2 cost / (m - n)): scales the covariance
  Vec2d pivot_px = Vec2d::Zero();           ///< centre of the registration's rotation and scale

  double value(const std::string& name) const;
  Similarity2D registration() const;
  double cycles_per_photo() const;
};

/// Observed volume samples (m³) at times (s); with cycles_per_photo and the sequence's
/// interval they map to cycles.
struct VolumeSeries {
  std::vector<double> time_s, volume_m3;
};

/// Fits. Throws InputError for bad parameters (unknown name, initial outside bounds) or
/// observations without a usable photo.
FitResult fit_sequence(const ObservationSequence& observations, FitModel& model,
                       const std::vector<FitParameter>& parameters, const FitOptions& options,
                       const std::optional<VolumeSeries>& volume = std::nullopt);

/// The registration of a parameter list (reg.* values; identity for missing ones).
Similarity2D registration_of(const std::map<std::string, double>& values, const Vec2d& pivot_px);

}  // namespace meltlab::verify
