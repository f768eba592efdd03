#pragma once

// The constant-curvature arc of the distal section, templated on the scalar
// so that Ceres can differentiate it (arc fitting, base-pose estimation).
//
// The arc starts at the origin heading along +y. Its curvature vector is
// (kappa_x, 0, kappa_z): the rate at which the section's frame turns about
// the x and z axes per mm of arc. kappa_x > 0 bends the tip toward +z,
// kappa_z > 0 toward -x. Written with sin(t)/t and (1 - cos t)/t^2 of
// t^2 = s^2 |kappa|^2, so it stays smooth, and differentiable, through the
// straight configuration.

#include <Eigen/Core>
#include <cmath>

namespace shapesense {

// sin(t)/t and (1 - cos t)/t^2 from t^2, with series near t = 0.
template <class T>
void ArcShapeFunctions(const T& t_squared, T* sinc, T* versine_over_t_squared) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  if (t_squared < T(1e-6)) {
    *sinc = T(1.0) - t_squared / 6.0 + t_squared * t_squared / 120.0;
    *versine_over_t_squared = T(0.5) - t_squared / 24.0 + t_squared * t_squared / 720.0;
    return;
  }
  const T t = sqrt(t_squared);
  const T half_sine = sin(t / 2.0);
  *sinc = sin(t) / t;
  *versine_over_t_squared = 2.0 * half_sine * half_sine / t_squared;
}

// Point at arc length s, in the frame of the arc's start.
template <class T>
Eigen::Matrix<T, 3, 1> ArcPoint(const T& kappa_x, const T& kappa_z, const T& s) {
  T sinc, versine;
  ArcShapeFunctions<T>(s * s * (kappa_x * kappa_x + kappa_z * kappa_z), &sinc, &versine);
  const T lateral = s * s * versine;
  return Eigen::Matrix<T, 3, 1>(-kappa_z * lateral, s * sinc, kappa_x * lateral);
}

}  // namespace shapesense
