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
// A weighing experiment (a mass series and no photos, issue 19) is fitted from those
// residuals alone, with the time scale in seconds per cycle: the reading at time t is the
// model at cycle first_cycle + t / seconds_per_cycle, and the mesh is scaled to the initial
// volume (VolumeSeries::initial_volume_m3): V_model(t) = V_mesh(c(t)) V_0 / V_mesh(0). From a
// mass curve alone kg and seconds_per_cycle are one parameter (only the melt per second
// kg / seconds_per_cycle shows): fitting both is refused before any simulation, and any two
// free parameters that the fit finds correlated beyond |r| = 0.995 are refused after it,
// naming the pair, rather than returned with huge errors.
//
// Uncertainty (issue 19). FitEstimate::standard_error is Ceres' covariance scaled by the
// residual variance: it treats every residual as independent. The 50 contour residuals of
// one photo are not (a photo whose contour is off by a bias moves all of them together), so
// FitEstimate::standard_error_clustered is the cluster-robust (sandwich) covariance with a
// photo as the cluster (a run of consecutive readings for a series):
//   V = G/(G-1) A⁻¹ B A⁻¹,  A = Σ_k w_k J_kᵀ J_k,  B = Σ_k w_k² J_kᵀ r_k r_kᵀ J_k,
// J_k, r_k the Jacobian and residuals of cluster k at the optimum, w_k its Huber weight, G the
// number of clusters. Its coverage is what the fit_coverage experiment measures. What it
// cannot see is a bias common to all photos: the segmentation's sub-pixel offset of the photo
// contours. FitEstimate::segmentation_bias estimates that separately: every photo segmented
// again with the threshold half-way between the levels of the ice and the ground next to its
// contour (where a blurred edge crosses), and the change of the estimate to first order
// (Gauss-Newton from the optimum). It is a systematic error estimate, not part of either
// standard error; its sign is not a reliable correction (the fit_coverage experiment: the
// estimate minus it was not closer to the truth), its size is the size of the error that
// the choice of the segmentation's level makes. FitEstimate::standard_error_total combines
// the two, sqrt(clustered² + bias²) (the GUM's way with a known but uncorrected systematic
// effect): the error bar whose coverage the fit_coverage experiment checks.
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
//   seconds_per_cycle  (a series alone) the reading at t is cycle first_cycle + t / S, blended
//                      the same way
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
  std::vector<double> kg_scan;       ///< factors of kg's initial value tried first (empty = no scan)
  double volume_weight = 0;          ///< weight of the volume residuals (0 = not used)
  std::vector<int> frames;           ///< frames (0-based) to fit; empty = all readable
  bool initial_registration = true;  ///< start free reg.* parameters from register_masks on the first photo
  /// A series alone with seconds_per_cycle free: start it where the model at the starting
  /// values falls to the relative mass of the reading nearest half the initial one (or the
  /// last reading) at that reading's time. Off when the caller gives the start.
  bool start_time_scale = false;
  std::int64_t max_cycles = 1000000;  ///< a series mapped beyond this cycle is an infeasible step
  /// Readings per cluster of a series' clustered standard error (0: n^(1/3), at least 1).
  int series_cluster_size = 0;
  /// Estimate the segmentation bias (photos; re-segments every photo once).
  bool segmentation_bias = true;
  std::function<void(const std::string&)> log;  ///< one line per event (scan, iteration)
};

struct FitEstimate {
  std::string name;
  double value = 0;
  double initial = 0;
  std::optional<double> standard_error;            ///< Ceres' covariance (independent residuals)
  std::optional<double> standard_error_clustered;  ///< cluster-robust: a photo (run of readings) per cluster
  std::optional<double> segmentation_bias;         ///< estimated systematic shift (photos), not in the errors above
  /// The error bar to quote: hypot(clustered, segmentation_bias), or the clustered error
  /// where there is no segmentation (a series) or no estimate of its bias.
  std::optional<double> standard_error_total;
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
  // Uncertainty beyond Ceres' covariance (see the header comment).
  std::string cluster_kind;  ///< "photo", "readings" (a run of consecutive readings), or empty
  int clusters = 0;          ///< G of the clustered standard errors
  int readings_per_cluster = 0;
  std::vector<std::vector<double>> correlation_clustered;  ///< free x free, empty if not computable
  /// Per used frame: the mean outward offset (px) of the mid-level contour from the fitted
  /// one (area difference / perimeter); positive: the segmentation drew the photo too small.
  std::vector<double> segmentation_offset_px;
  int uncertainty_evaluations = 0;  ///< simulations spent after the solve (0 when all were cached)
  /// A series: the fitted model's volume (m³) at every reading, at the estimates.
  std::vector<double> volume_fitted_m3;
  /// What the fit noticed that biases it, one line each (e.g. a model in several pieces
  /// where the segmentation keeps only the largest component).
  std::vector<std::string> warnings;

  double value(const std::string& name) const;
  Similarity2D registration() const;
  double cycles_per_photo() const;
};

/// Observed volume samples (m³) at times (s); with cycles_per_photo and the sequence's
/// interval they map to cycles (with seconds_per_cycle, a series alone: t / S).
struct VolumeSeries {
  std::vector<double> time_s, volume_m3;
  /// The volume at t = 0 the mesh is scaled to (a series alone: the model's volume is then
  /// relative, V_mesh(c) / V_mesh(0) times this, and residuals are relative to it). Unset: the
  /// mesh's own volume in m³ against volume_m3 (a mesh in metres), relative to volume_m3[0].
  std::optional<double> initial_volume_m3;
};

/// Fits. Throws InputError for bad parameters (unknown name, initial outside bounds),
/// observations without a usable photo, or (a series alone) parameters the series cannot
/// identify.
FitResult fit_sequence(const ObservationSequence& observations, FitModel& model,
                       const std::vector<FitParameter>& parameters, const FitOptions& options,
                       const std::optional<VolumeSeries>& volume = std::nullopt);

/// The registration of a parameter list (reg.* values; identity for missing ones).
Similarity2D registration_of(const std::map<std::string, double>& values, const Vec2d& pivot_px);

}  // namespace meltlab::verify
