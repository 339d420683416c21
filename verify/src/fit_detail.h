#pragma once
// The stages of verify/fit (internal to meltlab_verify):
//   fit_contour.cpp    contour geometry: segments, signed distances, contour samples, SDF images
//   fit_evaluator.cpp  the model evaluator: residuals per parameter vector, with its caches
//   fit_cost.cpp       the Ceres cost functor (central differences) and iteration logging
//   fit.cpp            targets, initial registration, kg scan, build_problem, solve, covariance

#include <meltlab/verify/fit.h>
#include <meltlab/verify/fit_parameters.h>
#include <meltlab/verify/region.h>

#include <ceres/ceres.h>
#include <opencv2/core.hpp>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace meltlab::verify::fit_detail {

// ---------------------------------------------------------------- contour geometry (px)

struct Segment {
  Vec2d a, b;
};

/// The segments of every loop (outer and holes) of a region.
std::vector<Segment> segments_of(const Region& region);
double point_segment_distance(const Vec2d& p, const Segment& s);
/// Even-odd point-in-region over all loops (pixel coordinates).
bool inside(const Vec2d& p, const std::vector<Segment>& segs);
/// Distance to the nearest segment, negative inside.
double signed_distance(const Vec2d& p, const std::vector<Segment>& segs);
/// `n` points spread evenly (by arc length) over all loops of a region.
std::vector<Vec2d> sample_contour(const std::vector<Segment>& segs, int n);
/// Bilinear lookup with clamping at the border (CV_32FC1).
double bilinear(const cv::Mat& f, const Vec2d& p);
/// Signed distance (px) to the boundary of a binary mask, negative inside; the boundary is
/// taken half-way between pixel centres.
cv::Mat signed_distance_image(const cv::Mat& mask);

// ---------------------------------------------------------------- targets

/// One photo as the fit sees it: its contour, samples on it and its signed distance field.
struct PhotoTarget {
  int frame = 0;        ///< 0-based index in the sequence
  double position = 0;  ///< photo position in units of photos (time / interval, or index)
  std::vector<Segment> segs;
  std::vector<Vec2d> samples;
  double area = 0, perimeter = 0;
  cv::Rect bbox;  ///< photo pixels, with margin, clamped to the image
  cv::Mat sdf;    ///< signed distance to the photo contour, in photo pixels
  cv::Mat mask;
};

// ---------------------------------------------------------------- the model evaluator

struct Evaluation {
  std::vector<std::vector<double>> frame_residuals;  ///< per target
  std::vector<double> volume_residuals;
  std::vector<double> volume_model;  ///< the model's volume (m³, scaled as the residuals) per sample
};

/// Residuals for a parameter vector (physical units, in the order of `params`). The
/// simulation and renders of one set of model values and time scale are cached and shared by
/// all registrations; whole evaluations are cached by parameter vector and shared by the
/// residual blocks.
class Evaluator {
 public:
  Evaluator(const ObservationSequence& obs, FitModel& model, std::vector<FitParameter> params,
            const FitOptions& options, std::vector<PhotoTarget> targets, const std::optional<VolumeSeries>& volume,
            Vec2d pivot)
      : obs_(obs),
        model_(model),
        params_(std::move(params)),
        o_(options),
        targets_(std::move(targets)),
        volume_(volume),
        pivot_(pivot) {}

  std::size_t residuals_per_frame() const { return static_cast<std::size_t>(o_.photo_samples) + 2; }
  const std::vector<PhotoTarget>& targets() const { return targets_; }
  const std::vector<FitParameter>& params() const { return params_; }
  int simulations() const { return simulations_; }
  /// The registration the render windows are placed by (the fit's starting one).
  void set_initial_registration(const Similarity2D& t) { initial_registration_ = t; }

  std::map<std::string, double> values_of(const std::vector<double>& x) const;
  std::shared_ptr<const Evaluation> evaluate(const std::vector<double>& x);
  /// The residuals of other photo targets (one per target of this evaluator, same frames)
  /// against the renders at x: the photos segmented another way, same model.
  std::vector<std::vector<double>> residuals_against(const std::vector<double>& x,
                                                     const std::vector<PhotoTarget>& others);
  /// Per target: how many separate pieces of at least `min_area_px` the rendered silhouette
  /// at x has (of the nearer of the two cycles a photo blends).
  std::vector<int> rendered_pieces(const std::vector<double>& x, double min_area_px);

 private:
  /// The rendered contours (render pixel coordinates) every photo needs, for one set of
  /// model values and time scale: the expensive part (a simulation and a render per photo),
  /// shared by all registrations.
  struct Renders {
    struct Need {
      std::size_t target;
      double weight;
      Region region;
    };
    std::vector<Need> needs;
    std::vector<double> volume_model;  ///< per volume sample (blended)
  };

  std::shared_ptr<const Renders> renders(const std::map<std::string, double>& model_values, double K,
                                         std::optional<double> seconds_per_cycle);
  /// renders() for the model values and time scale among `values` (all parameters by name).
  std::shared_ptr<const Renders> renders_at(const std::map<std::string, double>& values);
  /// Per target: its photo's residuals against each render it needs, placed by `reg`, summed
  /// with the needs' weights.
  std::vector<std::vector<double>> weighted_frame_residuals(const Renders& rs, const std::vector<PhotoTarget>& targets,
                                                            const Similarity2D& reg) const;
  Evaluation compute(const std::vector<double>& x);
  Region render_region(std::size_t target, const sim::TriMesh<double>& mesh, cv::Mat& coverage);
  std::vector<double> frame_residuals(const PhotoTarget& t, const Region& region) const;

  const ObservationSequence& obs_;
  FitModel& model_;
  std::vector<FitParameter> params_;
  FitOptions o_;
  std::vector<PhotoTarget> targets_;
  std::optional<VolumeSeries> volume_;
  Vec2d pivot_;
  std::map<std::vector<double>, std::shared_ptr<const Evaluation>> cache_;
  std::map<std::vector<double>, std::shared_ptr<const Renders>> render_cache_;
  int simulations_ = 0;
  Similarity2D initial_registration_;
};

// ---------------------------------------------------------------- cost functors

/// One residual block: a photo's residuals (or the volume residuals, target -1), as functions
/// of all parameters (one 1-D block each, in units of their scale), with central differences.
class BlockCost final : public ceres::CostFunction {
 public:
  BlockCost(Evaluator& ev, int target, int count, double step, std::vector<double> lower_u,
            std::vector<double> upper_u);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  bool evaluate(double const* const* parameters, double* residuals, double** jacobians) const;
  std::vector<double> residuals_at(const std::vector<double>& u) const;

  Evaluator& ev_;
  int target_;
  double step_;
  std::vector<double> lower_u_, upper_u_;
};

/// Logs one line per Ceres iteration through FitOptions::log.
class LogIterations final : public ceres::IterationCallback {
 public:
  LogIterations(const FitOptions& o, const Evaluator& ev) : o_(o), ev_(ev) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override;

 private:
  const FitOptions& o_;
  const Evaluator& ev_;
};

/// Ceres' Huber loss of one block's squared norm (the cost the solver sees), for the scan
/// and the initial cost.
double huber_cost(const std::vector<double>& r, double a);

}  // namespace meltlab::verify::fit_detail
