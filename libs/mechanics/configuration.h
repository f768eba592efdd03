#pragma once

// The configuration of a two-section continuum manipulator and the names
// the files use for its parts (docs/mechanics.md).

#include <Eigen/Core>
#include <array>

namespace shapesense {

// [kappa_x, kappa_z, eps0, eps1]: curvatures of the distal section about the
// base x and z axes (1/mm) and axial compressive strains of the proximal and
// distal sections.
using Configuration = Eigen::Vector4d;
// diag(K_m) = [K_x, K_z, K_a0, K_a1] (N*mm^2, N*mm^2, N, N).
using StiffnessVector = Eigen::Vector4d;

enum ConfigurationIndex { kKappaX = 0, kKappaZ = 1, kStrainProximal = 2, kStrainDistal = 3 };

// Names of the stiffnesses as in the model file, in StiffnessVector order.
inline constexpr std::array<const char*, 4> kStiffnessNames = {"bend_x", "bend_z", "axial_proximal",
                                                               "axial_distal"};
// Names of the configuration components as in the pose CSV.
inline constexpr std::array<const char*, 4> kConfigurationNames = {"kappa_x", "kappa_z", "eps0",
                                                                   "eps1"};

// Lengths of the two sections at rest, mm.
struct SectionLengths {
  double proximal = 0.0;  // L0
  double distal = 0.0;    // L1
};

}  // namespace shapesense
