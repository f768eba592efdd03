#include "libs/mechanics/manipulator_options.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "libs/config/options_yaml.h"
#include "libs/core/error.h"

namespace shapesense {
namespace {

// "" when value > 0 and finite, else "key: expected a positive number, got v".
std::string ExpectPositive(const std::string& key, double value) {
  if (std::isfinite(value) && value > 0.0) return "";
  return key + ": expected a positive number, got " + Number(value);
}

// Tendons closer to the axis than this carry no moment worth counting, mm.
constexpr double kOnAxisRadius = 1e-9;

}  // namespace

std::string TendonOptions::Validate() const {
  for (const std::string& error :
       {ExpectFinite("dx", dx), ExpectFinite("dz", dz), ExpectPositive("length", length),
        ExpectPositive("stiffness", stiffness)}) {
    if (!error.empty()) return error;
  }
  return "";
}

std::string StiffnessOptions::Validate() const {
  for (const std::string& error :
       {ExpectPositive("stiffness.bend_x", bend_x), ExpectPositive("stiffness.bend_z", bend_z),
        ExpectPositive("stiffness.axial_proximal", axial_proximal),
        ExpectPositive("stiffness.axial_distal", axial_distal)}) {
    if (!error.empty()) return error;
  }
  return "";
}

double TendonLayoutGap(const std::vector<TendonOptions>& tendons) {
  std::vector<double> angles;
  for (const TendonOptions& tendon : tendons) {
    if (std::hypot(tendon.dx, tendon.dz) > kOnAxisRadius) {
      angles.push_back(std::atan2(tendon.dz, tendon.dx));
    }
  }
  if (angles.empty()) return 2.0 * std::numbers::pi;
  std::sort(angles.begin(), angles.end());
  double gap = angles.front() + 2.0 * std::numbers::pi - angles.back();
  for (size_t i = 1; i < angles.size(); ++i) gap = std::max(gap, angles[i] - angles[i - 1]);
  return gap;
}

std::string ManipulatorOptions::Validate() const {
  if (std::string error = ExpectPositive("proximal_length", proximal_length); !error.empty()) {
    return error;
  }
  if (std::string error = ExpectPositive("distal_length", distal_length); !error.empty()) {
    return error;
  }
  if (tendons.size() < 3) {
    return "tendons: expected at least 3 tendons, got " + std::to_string(tendons.size());
  }
  for (size_t i = 0; i < tendons.size(); ++i) {
    if (std::string error = tendons[i].Validate(); !error.empty()) {
      return "tendons[" + std::to_string(i) + "]." + error;
    }
  }
  // A margin of 1e-6 rad keeps layouts with two tendons exactly opposite (a
  // gap of exactly pi, one bending axis missing) on the rejected side.
  const double gap = TendonLayoutGap(tendons);
  if (gap >= std::numbers::pi - 1e-6) {
    return "tendons: expected a layout that can bend about both axes (the neutral axis strictly "
           "inside the tendons' convex hull), got a gap of " +
           Number(gap * 180.0 / std::numbers::pi) + " degrees with no tendon";
  }
  return stiffness.Validate();
}

ManipulatorOptions ParseManipulatorYaml(const std::string& text, const std::string& source) {
  return OptionsFromYamlText<ManipulatorOptions>(text, source);
}

std::string FormatManipulatorYaml(const ManipulatorOptions& options) {
  return OptionsToDocumentedYaml(options);
}

}  // namespace shapesense
