#pragma once

// Stiffness estimation from sensed configurations (docs/mechanics.md).
//
//  - Tensionless (the reference's): from pairs (sensed q, commanded y), the
//    least-squares diag(K_m) of K_m q = D K_t L_t^-1 (y - D^T L0 q), one
//    stiffness per row.
//  - From tensions: from pairs (sensed q, measured tau), the least-squares
//    compliances of q = K_m^-1 D tau (q, the noisy side, is the response, so
//    the fit is not biased by its noise).
//  - Output error (past the reference): sensed q against the model's A(K_m) y,
//    Ceres over log-stiffnesses, each component weighted by its noise level
//    (re-estimated from the residuals). In the tensionless equation the sensed
//    q enters both sides, and with several tendons displaced at once q is
//    mostly fixed by the geometry (y ~ D^T L0 q), so the tendon stretch that
//    carries the stiffness information is a small difference of large
//    numbers: the tensionless estimate is biased and the stiffnesses can be
//    weakly identified. The output-error fit says how weakly: every
//    stiffness comes with its standard deviation from the fit's covariance,
//    and a warning names each one the poses leave poorly identified.
//
// All three report the model's residuals and are compared by the tip error
// (TipErrors) as a percentage of the distal length, like the reference's
// Table I.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "libs/mechanics/tendon_model.h"

namespace shapesense {

struct PoseSample {
  Eigen::VectorXd displacements;                        // y, commanded, mm
  Configuration configuration = Configuration::Zero();  // sensed q
  Eigen::VectorXd tensions;                             // measured tau, N; empty when not measured
};

struct StiffnessEstimate {
  std::string method;  // "tensionless", "tensions" or "output_error"
  bool valid = false;
  std::string message;  // why not valid, or the solver's message
  StiffnessVector stiffness = StiffnessVector::Zero();
  // One standard deviation of each stiffness, same units; infinite when the
  // poses do not constrain it at all.
  StiffnessVector standard_deviation = StiffnessVector::Zero();
  // RMS of sensed q minus the model's A(K) y over the poses, per component.
  Configuration residual_rms = Configuration::Zero();
  // E.g. "bend_z is poorly identified by these poses: its standard deviation
  // is 35% of the estimate (limit 10%)".
  std::vector<std::string> warnings;
};

struct EstimationOptions {
  // Initial noise levels of the sensed configuration, which weight its
  // components in the output-error fit until the residuals re-estimate them.
  double curvature_noise = 1e-4;  // 1/mm
  double strain_noise = 1e-4;
  // Weight by the noise levels the residuals show (a second fit).
  bool reweight_from_residuals = true;
  // A stiffness whose standard deviation exceeds this fraction of its value
  // is reported as poorly identified.
  double max_relative_std = 0.1;
  int max_iterations = 100;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("curvature_noise", curvature_noise,
          "initial noise level of the sensed curvatures, 1/mm (> 0)");
    visit("strain_noise", strain_noise, "initial noise level of the sensed strains (> 0)");
    visit("reweight_from_residuals", reweight_from_residuals,
          "re-weight by the noise the residuals show");
    visit("max_relative_std", max_relative_std,
          "warn when a stiffness's std exceeds this fraction of it (> 0)");
    visit("max_iterations", max_iterations, "solver iterations (> 0)");
  }
  std::string Validate() const;
};

// Each needs at least 2 poses with displacements of the model's tendon count
// (and tensions, for the tension-based one); otherwise valid = false.
StiffnessEstimate EstimateStiffnessTensionless(const TendonModel& model,
                                               const std::vector<PoseSample>& poses,
                                               const EstimationOptions& options);
StiffnessEstimate EstimateStiffnessFromTensions(const TendonModel& model,
                                                const std::vector<PoseSample>& poses,
                                                const EstimationOptions& options);
// Starts from the model's stiffnesses.
StiffnessEstimate EstimateStiffnessOutputError(const TendonModel& model,
                                               const std::vector<PoseSample>& poses,
                                               const EstimationOptions& options);

// Tip of the model's prediction A y against the tip of the sensed q, per
// pose, as a percentage of the distal length L1.
struct TipErrors {
  std::vector<double> percent;
  double mean = 0.0;
  double std = 0.0;  // sample standard deviation over the poses
  double max = 0.0;
};
TipErrors ComputeTipErrors(const TendonModel& model, const std::vector<PoseSample>& poses);

}  // namespace shapesense
