#pragma once

// What `shapesense estimate` prints and writes: each estimator's stiffnesses
// with their standard deviations, the model's tip error table (like the
// reference's Table I) and the warnings.

#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "libs/mechanics/stiffness_estimation.h"

namespace shapesense {

struct MethodResult {
  StiffnessEstimate estimate;
  TipErrors tip_errors;  // of the model with the estimated stiffnesses
};

struct EstimateReport {
  std::string model_source;
  std::string data_source;
  int num_poses = 0;
  double distal_length = 0.0;
  StiffnessVector nominal = StiffnessVector::Zero();  // from the model file
  TipErrors nominal_tip_errors;
  std::vector<MethodResult> methods;
  size_t primary = 0;  // index into methods of the estimate written as "stiffness"
};

// {"stiffness": {bend_x, bend_z, axial_proximal, axial_distal},
//  "tip_error_percent": {mean, std, max, per_pose}, "stiffness_std", "method",
//  "warnings", "estimates": [every method], "nominal": {...}, ...}.
// Standard deviations that are infinite are written as null.
nlohmann::json ReportToJson(const EstimateReport& report);

void PrintReport(const EstimateReport& report, std::ostream& out);

}  // namespace shapesense
