// The closed-loop experiment's report: a run's scores (scored on a synthetic
// truth stream, each target missed by a configuration of its own) go into
// report.json with every target and the means.
#include "clients/tools/demo/closed_loop_experiment.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "libs/evaluation/closed_loop_score.h"

namespace shapesense {
namespace {

const SectionLengths kRest{600.0, 160.0};  // config/manipulator.yaml
constexpr double kRate = 30.0;             // truth samples per second
constexpr double kWindow = 1.5;            // s

// Every target held at its q off by a random configuration of its own,
// sampled every 1/kRate s.
std::vector<ConfigurationSample> MissedTargets(const std::vector<ExperimentTarget>& targets) {
  std::mt19937 random(6);
  std::normal_distribution<double> noise(0.0, 5e-4);
  std::vector<ConfigurationSample> truth;
  for (const ExperimentTarget& target : targets) {
    const Configuration q = target.q + Configuration(noise(random), noise(random), 0.0, 0.0);
    for (int k = 0; k / kRate < targets.back().end_s; ++k) {
      const double time = k / kRate;
      if (time >= target.start_s && time < target.end_s) truth.push_back({time, q});
    }
  }
  return truth;
}

TEST(ClosedLoopExperiment, RunScoreJsonCarriesTheScores) {
  ExperimentTargetOptions options;
  options.count = 7;
  options.hold_s = 3.0;
  const std::vector<ExperimentTarget> targets = MakeExperimentTargets(options, kRest);
  const RunScore run = ScoreRun("open_loop", targets, MissedTargets(targets), kRest, kWindow);
  ASSERT_EQ(run.targets_scored, 7);
  const nlohmann::json json = RunScoreToJson(run);
  EXPECT_EQ(json["mode"], "open_loop");
  EXPECT_EQ(json["mean_tip_error_mm"].get<double>(), run.mean_tip_error_mm);
  EXPECT_GT(run.mean_tip_error_mm, 0.0);
  EXPECT_EQ(json["max_tip_error_mm"].get<double>(), run.max_tip_error_mm);
  EXPECT_EQ(json["mean_tip_error_percent"].get<double>(), run.mean_tip_error_percent);
  EXPECT_EQ(json["targets_scored"].get<int>(), 7);
  EXPECT_EQ(json["targets_within_1mm"].get<int>(), run.targets_within(1.0));
  ASSERT_EQ(json["targets"].size(), 7u);
  for (size_t i = 0; i < 7; ++i) {
    const nlohmann::json& t = json["targets"][i];
    EXPECT_EQ(t["index"].get<int>(), static_cast<int>(i));
    EXPECT_EQ(t["target_q"].get<std::vector<double>>()[0], targets[i].q(kKappaX));
    EXPECT_EQ(t["target_tip_mm"].get<std::vector<double>>()[1], run.targets[i].target_tip.y());
    EXPECT_EQ(t["mean_tip_mm"].get<std::vector<double>>()[2], run.targets[i].mean_tip.z());
    EXPECT_EQ(t["tip_error_mm"].get<double>(), run.targets[i].tip_error_mm);
    EXPECT_EQ(t["max_tip_error_mm"].get<double>(), run.targets[i].max_tip_error_mm);
    EXPECT_EQ(t["distal_tip_error_mm"].get<double>(), run.targets[i].distal_tip_error_mm);
    EXPECT_EQ(t["samples"].get<int>(), run.targets[i].samples);
  }
}

}  // namespace
}  // namespace shapesense
