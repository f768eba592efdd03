#pragma once

#include <vector>

#include "libs/geometry/types.h"

namespace shapesense {

// A space curve as a uniform cubic B-spline, fitted by penalised least squares
// (a P-spline, Eilers & Marx 1996): knots about `knot_spacing` apart over the
// parameter range of the data, and a penalty on the change of curvature,
//   minimise  d Σ w_i |p_i − c(u_i)|²  +  smoothing⁶ ∫ |c'''(u)|² du,
// where d is the mean spacing of the data, so the result does not depend on
// how densely the curve is sampled. `smoothing` is a length (mm): details
// shorter than about it are smoothed away; 0 leaves only the knots to smooth.
// Unlike a penalty on bending, this one does not flatten arcs: it vanishes on
// every quadratic.
// Outside its parameter range the curve continues along its end tangents.
class SmoothingSpline {
 public:
  SmoothingSpline() = default;

  // `u` ascending with at least two distinct values; `weights` empty (all 1)
  // or one per point, ≥ 0. Returns an empty spline when the data cannot
  // define a curve.
  static SmoothingSpline Fit(const std::vector<double>& u, const Polyline& points,
                             const std::vector<double>& weights, double knot_spacing,
                             double smoothing);

  bool empty() const { return control_.empty(); }
  double begin() const { return begin_; }
  double end() const { return begin_ + span_ * num_spans(); }

  Vec3 Point(double u) const;
  Vec3 Derivative(double u) const;
  Vec3 SecondDerivative(double u) const;

 private:
  int num_spans() const { return static_cast<int>(control_.size()) - 3; }
  // Span index and local parameter in [0, 1] of a parameter inside the range.
  int Locate(double u, double* t) const;

  double begin_ = 0.0;
  double span_ = 1.0;  // knot spacing in the parameter
  Polyline control_;
};

// Points of a curve at spacing ≤ `spacing` in arc length between parameters
// `u_begin` and `u_end`, both ends included; `params` receives each point's
// spline parameter.
Polyline SampleByArcLength(const SmoothingSpline& spline, double u_begin, double u_end,
                           double spacing, std::vector<double>* params);

}  // namespace shapesense
