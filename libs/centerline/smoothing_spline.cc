#include "libs/centerline/smoothing_spline.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>

namespace shapesense {
namespace {

// Uniform cubic B-spline basis on one span, local parameter t in [0, 1], and
// its first and second derivatives with respect to t.
std::array<double, 4> Basis(double t) {
  const double s = 1.0 - t;
  return {s * s * s / 6.0, (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
          (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0, t * t * t / 6.0};
}

std::array<double, 4> BasisDerivative(double t) {
  const double s = 1.0 - t;
  return {-0.5 * s * s, 1.5 * t * t - 2.0 * t, -1.5 * t * t + t + 0.5, 0.5 * t * t};
}

std::array<double, 4> BasisSecondDerivative(double t) {
  return {1.0 - t, 3.0 * t - 2.0, 1.0 - 3.0 * t, t};
}

// Enough data for a curve: positive weight at two distinct parameters.
bool DefinesACurve(const std::vector<double>& u, const std::vector<double>& weights) {
  double first = 0.0;
  bool have_first = false;
  for (size_t i = 0; i < u.size(); ++i) {
    if (!weights.empty() && !(weights[i] > 0.0)) continue;
    if (!have_first) {
      first = u[i];
      have_first = true;
    } else if (u[i] != first) {
      return true;
    }
  }
  return false;
}

}  // namespace

int SmoothingSpline::Locate(double u, double* t) const {
  const double x = (u - begin_) / span_;
  const int span = std::clamp(static_cast<int>(std::floor(x)), 0, num_spans() - 1);
  *t = std::clamp(x - span, 0.0, 1.0);
  return span;
}

SmoothingSpline SmoothingSpline::Fit(const std::vector<double>& u, const Polyline& points,
                                     const std::vector<double>& weights, double knot_spacing,
                                     double smoothing) {
  SmoothingSpline spline;
  if (u.size() != points.size() || (!weights.empty() && weights.size() != u.size()) ||
      !DefinesACurve(u, weights) || !(knot_spacing > 0.0)) {
    return spline;
  }
  const double length = u.back() - u.front();
  const int spans = std::max(1, static_cast<int>(std::lround(length / knot_spacing)));
  spline.begin_ = u.front();
  spline.span_ = length / spans;
  const int n = spans + 3;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
  spline.control_.resize(static_cast<size_t>(n), Vec3::Zero());
  double total_weight = 0.0;
  for (size_t i = 0; i < u.size(); ++i) total_weight += weights.empty() ? 1.0 : weights[i];
  const double data_scale = length / total_weight;  // the mean spacing of the data
  for (size_t i = 0; i < u.size(); ++i) {
    const double w = data_scale * (weights.empty() ? 1.0 : weights[i]);
    double t = 0.0;
    const int j = spline.Locate(u[i], &t);
    const std::array<double, 4> b = Basis(t);
    for (int a = 0; a < 4; ++a) {
      rhs.row(j + a) += w * b[static_cast<size_t>(a)] * points[i].transpose();
      for (int c = 0; c < 4; ++c) {
        normal(j + a, j + c) += w * b[static_cast<size_t>(a)] * b[static_cast<size_t>(c)];
      }
    }
  }
  // ∫|c'''|² du ≈ Σ |Δ³c_k|² / h⁵ (third differences of the control points
  // are h³ c''' between the knots). Penalising the change of curvature rather
  // than the curvature leaves arcs round: the penalty vanishes on every
  // quadratic. A tiny ridge keeps spans without data solvable.
  const double lambda = std::pow(smoothing, 6) / std::pow(spline.span_, 5) + 1e-9;
  const std::array<double, 4> third_difference = {-1.0, 3.0, -3.0, 1.0};
  for (int k = 0; k + 3 < n; ++k) {
    for (int a = 0; a < 4; ++a) {
      for (int c = 0; c < 4; ++c) {
        normal(k + a, k + c) += lambda * third_difference[static_cast<size_t>(a)] *
                                third_difference[static_cast<size_t>(c)];
      }
    }
  }
  const Eigen::MatrixXd solution = normal.ldlt().solve(rhs);
  for (int k = 0; k < n; ++k) spline.control_[static_cast<size_t>(k)] = solution.row(k).transpose();
  return spline;
}

Vec3 SmoothingSpline::Point(double u) const {
  double t = 0.0;
  const int j = Locate(u, &t);
  const std::array<double, 4> b = Basis(t);
  Vec3 p = Vec3::Zero();
  for (int a = 0; a < 4; ++a) p += b[static_cast<size_t>(a)] * control_[static_cast<size_t>(j + a)];
  const double outside = u < begin() ? u - begin() : (u > end() ? u - end() : 0.0);
  return outside == 0.0 ? p : Vec3(p + outside * Derivative(u));
}

Vec3 SmoothingSpline::Derivative(double u) const {
  double t = 0.0;
  const int j = Locate(u, &t);
  const std::array<double, 4> b = BasisDerivative(t);
  Vec3 d = Vec3::Zero();
  for (int a = 0; a < 4; ++a) d += b[static_cast<size_t>(a)] * control_[static_cast<size_t>(j + a)];
  return d / span_;
}

Vec3 SmoothingSpline::SecondDerivative(double u) const {
  if (u < begin() || u > end()) return Vec3::Zero();
  double t = 0.0;
  const int j = Locate(u, &t);
  const std::array<double, 4> b = BasisSecondDerivative(t);
  Vec3 d = Vec3::Zero();
  for (int a = 0; a < 4; ++a) d += b[static_cast<size_t>(a)] * control_[static_cast<size_t>(j + a)];
  return d / (span_ * span_);
}

Polyline SampleByArcLength(const SmoothingSpline& spline, double u_begin, double u_end,
                           double spacing, std::vector<double>* params) {
  // A fine polyline gives arc length as a function of the parameter; the
  // output points are then placed at equal steps of it.
  const int fine = std::max(2, static_cast<int>(std::ceil(4.0 * (u_end - u_begin) / spacing)));
  std::vector<double> fine_u(static_cast<size_t>(fine) + 1);
  std::vector<double> fine_arc(fine_u.size(), 0.0);
  Vec3 previous = spline.Point(u_begin);
  for (int k = 0; k <= fine; ++k) {
    fine_u[static_cast<size_t>(k)] = u_begin + (u_end - u_begin) * k / fine;
    const Vec3 p = spline.Point(fine_u[static_cast<size_t>(k)]);
    if (k > 0)
      fine_arc[static_cast<size_t>(k)] =
          fine_arc[static_cast<size_t>(k) - 1] + (p - previous).norm();
    previous = p;
  }
  const double length = fine_arc.back();
  const int steps = std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9)));
  Polyline points;
  params->clear();
  size_t k = 1;
  for (int i = 0; i <= steps; ++i) {
    const double s = length * i / steps;
    while (k + 1 < fine_arc.size() && fine_arc[k] < s) ++k;
    const double run = fine_arc[k] - fine_arc[k - 1];
    const double f = run > 0.0 ? std::clamp((s - fine_arc[k - 1]) / run, 0.0, 1.0) : 0.0;
    params->push_back(fine_u[k - 1] + f * (fine_u[k] - fine_u[k - 1]));
    points.push_back(spline.Point(params->back()));
  }
  return points;
}

}  // namespace shapesense
