#pragma once

// The manipulator model file (config/manipulator.yaml; docs/mechanics.md):
//
//   proximal_length: 600        # L0, mm
//   distal_length: 160          # L1, mm
//   tendons:                    # n >= 3, in the cross-section (x, z) of the base frame
//     - {dx: 1.2, dz: 0, length: 900, stiffness: 6000}   # mm, mm, mm, N
//     - ...
//   stiffness: {bend_x: 400, bend_z: 400, axial_proximal: 2500, axial_distal: 800}
//
// Parsing works on YAML text; reading the file is the caller's job.

#include <string>
#include <vector>

namespace shapesense {

struct TendonOptions {
  // Moment arm: where the tendon runs in the cross-section, mm.
  double dx = 0.0;
  double dz = 0.0;
  // Free length of the tendon between its anchor at the tip and the actuator, mm.
  double length = 0.0;
  // Axial stiffness E·A of the tendon, N (stretch = tension · length / stiffness).
  double stiffness = 0.0;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("dx", dx, "moment arm along x, mm");
    visit("dz", dz, "moment arm along z, mm");
    visit("length", length, "tendon length L_t, mm (> 0)");
    visit("stiffness", stiffness, "tendon axial stiffness K_t = E*A, N (> 0)");
  }
  // "" or "key: what", keys relative to this tendon.
  std::string Validate() const;
};

struct StiffnessOptions {
  double bend_x = 400.0;           // K_x, N·mm²
  double bend_z = 400.0;           // K_z, N·mm²
  double axial_proximal = 2500.0;  // K_a0, N
  double axial_distal = 800.0;     // K_a1, N

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("bend_x", bend_x, "bending stiffness about x, K_x = E*I, N*mm^2 (> 0)");
    visit("bend_z", bend_z, "bending stiffness about z, K_z = E*I, N*mm^2 (> 0)");
    visit("axial_proximal", axial_proximal,
          "axial stiffness of the proximal section, K_a0 = E*A, N (> 0)");
    visit("axial_distal", axial_distal,
          "axial stiffness of the distal section, K_a1 = E*A, N (> 0)");
  }
  std::string Validate() const;
};

struct ManipulatorOptions {
  double proximal_length = 600.0;  // L0, mm
  double distal_length = 160.0;    // L1, mm
  // No default: a model file must list its tendons.
  std::vector<TendonOptions> tendons;
  StiffnessOptions stiffness;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("proximal_length", proximal_length,
          "length L0 of the straight proximal section, mm (> 0)");
    visit("distal_length", distal_length, "length L1 of the bending distal section, mm (> 0)");
    visit(
        "tendons", tendons,
        "tendons {dx, dz, length, stiffness} (mm, mm, mm, N); at least 3, around the neutral axis");
    visit("stiffness", stiffness,
          "manipulator stiffness K_m = diag(bend_x, bend_z, axial_proximal, axial_distal)");
  }
  // Also rejects a tendon layout that cannot bend the distal section in every
  // direction with positive tensions (see TendonLayoutGap).
  std::string Validate() const;
};

// Largest angle around the neutral axis, rad, with no tendon in it (tendons
// on the axis do not count). Positive tensions can bend the section in every
// direction, about both axes, exactly when this is below pi: the neutral axis
// lies strictly inside the tendons' convex hull.
double TendonLayoutGap(const std::vector<TendonOptions>& tendons);

// Throws InputError("source: key: what") on bad YAML, unknown keys, wrong
// types or values that fail Validate().
ManipulatorOptions ParseManipulatorYaml(const std::string& text, const std::string& source);

// YAML with every key documented; parses back to the same options.
std::string FormatManipulatorYaml(const ManipulatorOptions& options);

}  // namespace shapesense
