#pragma once
// Seed 001's transfer functions (spec ../shared/spec/cpu-large-volumes.md §2.3, §3): a 1-D,
// piecewise-constant map from a sample value to a colour (0-255 units, as the source) and an
// opacity α ∈ [0, 1], applied after interpolation (clv.tf.classification: post), so it is
// evaluated for every sample of every frame; and the opacity correction for the sampling step.
//
// A range's bounds are open or closed ("(85, 95]"); ranges may not overlap; a value in no range
// has α = 0 (and no colour). The tables of the spec (value ranges half-open as written there):
//   shapes:  (85, 95] → (255, 30, 60), α 0.02;  (95, 100] → (10, 60, 180), α 0.3;
//            (100, 115) → (90, 210, 20), α 0.6
//   skull:   (40, 240) → (255, 255, 255), α 1   (the repo's colour is not given; white)
//
// Seed 003 (spec ../shared/spec/volume-slicing-importance.md §2.4) adds the second kind of the same
// concept: a piecewise-LINEAR RGBA TF edited as per-channel curves through control points
// (x = the normalised value, y = the channel in [0, 1]; constant beyond the first and last point).
// Both kinds answer evaluate(v) (colour in [0, 1] units: a constant TF's 0-255 colour / 255),
// visible_at and visible_in; the ray caster's TF model reads the constant kind only (its kernel
// tables the ranges), the slicing renderer (render/slicing/) either kind.
//
// The "characteristic" of a TF (the value ranges that map to α > 0) lets the empty-space indexes
// decide from a cell's [min, max] alone whether any interpolated value in it can be visible.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace meltlab::render {

/// One piecewise-constant piece.
struct TfRange {
  double lo = 0, hi = 0;
  bool lo_closed = false, hi_closed = true;
  Eigen::Vector3d rgb = Eigen::Vector3d::Zero();  ///< colour, 0-255 units
  double alpha = 0;                               ///< opacity for the reference step, [0, 1]

  bool contains(double v) const { return (lo_closed ? v >= lo : v > lo) && (hi_closed ? v <= hi : v < hi); }
  /// "(85, 95]".
  std::string bounds_text() const;
};

/// One channel of a piecewise-linear TF: control points (x, y), x strictly increasing.
struct TfCurve {
  std::vector<Eigen::Vector2d> points;
  /// y(x): linear between points, the end values beyond them; 0 for an empty curve.
  double at(double x) const;
  /// The largest y over the closed interval [lo, hi].
  double max_in(double lo, double hi) const;
};

/// The two kinds of transfer function.
enum class TfKind { kPiecewiseConstant, kPiecewiseLinear };

/// A TF value: colour in [0, 1] units and opacity α ∈ [0, 1].
struct TfValue {
  Eigen::Vector3d rgb = Eigen::Vector3d::Zero();
  double alpha = 0;
};

class TransferFunction {
 public:
  /// α = 0 everywhere.
  TransferFunction() = default;
  /// Throws InputError (naming `what`) for a range with lo > hi, an empty range, α outside [0, 1],
  /// a colour outside [0, 255] or not finite, or two ranges that overlap. Ranges are kept sorted.
  TransferFunction(std::vector<TfRange> ranges, std::string name = "custom",
                   const std::string& what = "transfer function");

  /// Seed 003's piecewise-linear TF from four curves (r, g, b, a). Throws InputError (naming
  /// `what`) for a curve with x not strictly increasing or not finite, or y outside [0, 1].
  static TransferFunction piecewise_linear(const std::array<TfCurve, 4>& rgba, std::string name = "linear",
                                           const std::string& what = "transfer function");

  TfKind kind() const { return kind_; }
  /// The curves of a piecewise-linear TF (r, g, b, a); empty for the constant kind.
  const std::array<TfCurve, 4>& curves() const { return curves_; }
  /// The TF at v (either kind; colour in [0, 1] units).
  TfValue evaluate(double v) const;
  /// α(v) alone (evaluate(v).alpha, bit for bit): callers skip the colour where it is 0.
  double alpha_at(double v) const;

  /// The spec's tables (§3).
  static TransferFunction shapes();
  static TransferFunction skull();
  /// "shapes" or "skull" (InputError naming `what` otherwise).
  static TransferFunction named(const std::string& name, const std::string& what);

  const std::vector<TfRange>& ranges() const { return ranges_; }
  const std::string& name() const { return name_; }
  /// Index of the range containing v, or -1 (α = 0).
  int find(double v) const;
  /// α(v) > 0.
  bool visible_at(double v) const;
  /// Whether some value in the closed interval [lo, hi] has α > 0 (lo <= hi): the characteristic.
  bool visible_in(double lo, double hi) const;

 private:
  std::vector<TfRange> ranges_;
  std::string name_ = "none";
  TfKind kind_ = TfKind::kPiecewiseConstant;
  std::array<TfCurve, 4> curves_;
};

/// Parses "(85, 95]" / "[0, 1)" ... into a range's bounds (colour and α left as they are).
/// Throws InputError naming `what`.
void parse_tf_bounds(const std::string& text, TfRange& range, const std::string& what);

/// clv.tf.opacity_exponent: the correction α = 1 - (1 - α₀)^x for a step s, the TF made for s₀.
enum class OpacityExponent {
  kStepOverReference,  ///< x = s / s₀ (correct; the repo)
  kReferenceOverStep,  ///< x = s₀ / s (as printed in the thesis [2.3]: an erratum, kept to show it)
};
double corrected_opacity(double alpha, double step, double reference_step, OpacityExponent exponent);
std::string opacity_exponent_name(OpacityExponent e);

}  // namespace meltlab::render
