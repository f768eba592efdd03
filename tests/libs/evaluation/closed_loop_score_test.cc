// The closed-loop experiment's scoring on synthetic truth streams (about
// 30 Hz, like the rig's): truth at the target scores zero; truth off by known
// configurations scores the tip distance of an arc computed here
// independently; eps0 drops out of the distal error; samples outside the
// steady-state window are ignored and a target without any is left out of
// the means. Then the table carries every target and the means, the
// experiment's targets are spread within the bend limit as a short tour, and
// the picture changes where a run is drawn. (The JSON of a run's scores is
// the demo's: tests/clients/demo/closed_loop_experiment_test.cc.)
#include "libs/evaluation/closed_loop_score.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <iomanip>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>

#include "libs/evaluation/closed_loop_plot.h"
#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

const SectionLengths kRest{600.0, 160.0};  // config/manipulator.yaml
constexpr double kRate = 30.0;             // truth samples per second
constexpr double kWindow = 1.5;            // s

// Tip of the constant-curvature model, written out: the shaft straight along
// +y for L0 (1 - eps0), then an arc of L1 (1 - eps1) turning about the
// curvature vector (kappa_x, 0, kappa_z); the frame's y axis goes to
// cos(k s) y + sin(k s) (axis x y). `distal_only` leaves the shaft out.
Vec3 IndependentTip(const Configuration& q, bool distal_only = false) {
  const double shaft = distal_only ? 0.0 : kRest.proximal * (1.0 - q(kStrainProximal));
  const double length = kRest.distal * (1.0 - q(kStrainDistal));
  const Vec3 curvature(q(kKappaX), 0.0, q(kKappaZ));
  const double k = curvature.norm();
  if (k < 1e-12) return Vec3(0.0, shaft + length, 0.0);
  const Vec3 side = (curvature / k).cross(Vec3::UnitY());
  return Vec3(0.0, shaft, 0.0) + std::sin(k * length) / k * Vec3::UnitY() +
         (1.0 - std::cos(k * length)) / k * side;
}

Configuration RandomConfiguration(std::mt19937& random) {
  std::uniform_real_distribution<double> kappa(-0.007, 0.007), strain(0.0, 0.01);
  return Configuration(kappa(random), kappa(random), strain(random), strain(random));
}

std::vector<ExperimentTarget> SomeTargets(int count, uint32_t seed = 5) {
  ExperimentTargetOptions options;
  options.count = count;
  options.hold_s = 3.0;
  options.seed = seed;
  return MakeExperimentTargets(options, kRest);
}

// Samples every 1/kRate s over all the targets, q given by `truth_at(target, time)`.
template <class TruthAt>
std::vector<ConfigurationSample> TruthStream(const std::vector<ExperimentTarget>& targets,
                                             TruthAt truth_at) {
  std::vector<ConfigurationSample> samples;
  for (int k = 0; k / kRate < targets.back().end_s; ++k) {
    const double time = k / kRate;
    for (size_t i = 0; i < targets.size(); ++i) {
      if (time >= targets[i].start_s && time < targets[i].end_s) {
        samples.push_back({time, truth_at(i, time)});
      }
    }
  }
  return samples;
}

int SamplesIn(const std::vector<ConfigurationSample>& truth, double from, double to) {
  return static_cast<int>(std::count_if(truth.begin(), truth.end(), [&](const auto& s) {
    return s.time_s >= from && s.time_s < to;
  }));
}

TEST(ClosedLoopScore, IndependentTipAgreesWithTheModel) {
  std::mt19937 random(1);
  for (int trial = 0; trial < 50; ++trial) {
    const Configuration q = RandomConfiguration(random);
    const Pose3 tip = BaseFromTip(q, kRest);
    EXPECT_LT((tip.translation() - IndependentTip(q)).norm(), 1e-9);
  }
}

TEST(ClosedLoopScore, TruthAtTheTargetScoresZero) {
  const std::vector<ExperimentTarget> targets = SomeTargets(6);
  const auto truth = TruthStream(targets, [&](size_t i, double) { return targets[i].q; });
  const RunScore run = ScoreRun("closed_loop", targets, truth, kRest, kWindow);
  ASSERT_EQ(run.targets.size(), targets.size());
  EXPECT_EQ(run.targets_scored, 6);
  EXPECT_EQ(run.targets_within(1e-9), 6);
  EXPECT_NEAR(run.mean_tip_error_mm, 0.0, 1e-9);
  for (const TargetScore& t : run.targets) {
    EXPECT_EQ(t.samples,
              SamplesIn(truth, targets[t.index].end_s - kWindow, targets[t.index].end_s));
    EXPECT_LT((t.target_tip - IndependentTip(targets[t.index].q)).norm(), 1e-9);
    EXPECT_LT((t.mean_tip - t.target_tip).norm(), 1e-9);
  }
}

// The truth alternates between two random configurations in each window, so
// the mean and the worst error differ and both are known.
TEST(ClosedLoopScore, ErrorsAreTheTipDistancesOfTheTruth) {
  std::mt19937 random(2);
  std::vector<ExperimentTarget> targets = SomeTargets(8);
  for (ExperimentTarget& target : targets) target.q = RandomConfiguration(random);
  std::vector<std::array<Configuration, 2>> seen;
  for (size_t i = 0; i < targets.size(); ++i) {
    seen.push_back({RandomConfiguration(random), RandomConfiguration(random)});
  }
  const auto truth = TruthStream(
      targets, [&](size_t i, double time) { return seen[i][std::lround(time * kRate) % 2]; });
  const RunScore run = ScoreRun("open_loop", targets, truth, kRest, kWindow);
  double sum = 0.0, worst = 0.0;
  for (size_t i = 0; i < targets.size(); ++i) {
    const Vec3 wanted = IndependentTip(targets[i].q);
    const double a = (IndependentTip(seen[i][0]) - wanted).norm();
    const double b = (IndependentTip(seen[i][1]) - wanted).norm();
    const TargetScore& score = run.targets[i];
    // The window holds 45 samples, 22 of one kind and 23 of the other.
    EXPECT_NEAR(score.tip_error_mm, 0.5 * (a + b), 0.02 * std::abs(a - b) + 1e-9);
    EXPECT_NEAR(score.max_tip_error_mm, std::max(a, b), 1e-9);
    const Vec3 mean = 0.5 * (IndependentTip(seen[i][0]) + IndependentTip(seen[i][1]));
    EXPECT_LT((score.mean_tip - mean).norm(),
              0.02 * (IndependentTip(seen[i][0]) - IndependentTip(seen[i][1])).norm() + 1e-9);
    sum += score.tip_error_mm;
    worst = std::max(worst, score.tip_error_mm);
  }
  EXPECT_NEAR(run.mean_tip_error_mm, sum / targets.size(), 1e-9);
  EXPECT_NEAR(run.max_tip_error_mm, worst, 1e-12);
  EXPECT_NEAR(run.mean_tip_error_percent, run.mean_tip_error_mm / kRest.distal * 100.0, 1e-12);
}

TEST(ClosedLoopScore, DistalErrorLeavesTheShaftCompressionOut) {
  std::mt19937 random(3);
  std::vector<ExperimentTarget> targets = SomeTargets(5);
  std::vector<Configuration> seen;
  for (ExperimentTarget& target : targets) {
    target.q = RandomConfiguration(random);
    seen.push_back(RandomConfiguration(random));
  }
  // Same distal section, the shaft compressed by 1 % more: only the proximal length differs.
  const auto truth = TruthStream(targets, [&](size_t i, double) {
    Configuration q = targets[i].q;
    q(kStrainProximal) += 0.01;
    return q;
  });
  const RunScore run = ScoreRun("open_loop", targets, truth, kRest, kWindow);
  for (const TargetScore& t : run.targets) {
    EXPECT_NEAR(t.tip_error_mm, 0.01 * kRest.proximal, 1e-9);
    EXPECT_NEAR(t.distal_tip_error_mm, 0.0, 1e-9);
  }
  // Any truth: the distal error is the distance of the arcs alone.
  const auto other = TruthStream(targets, [&](size_t i, double) { return seen[i]; });
  const RunScore bent = ScoreRun("open_loop", targets, other, kRest, kWindow);
  for (const TargetScore& t : bent.targets) {
    const double expected =
        (IndependentTip(seen[t.index], true) - IndependentTip(targets[t.index].q, true)).norm();
    EXPECT_NEAR(t.distal_tip_error_mm, expected, 1e-9);
  }
}

TEST(ClosedLoopScore, OnlyTheSteadyStateWindowCounts) {
  const std::vector<ExperimentTarget> targets = SomeTargets(5);
  // Far off while settling, exact in the last kWindow of each hold.
  const auto truth = TruthStream(targets, [&](size_t i, double time) {
    Configuration q = targets[i].q;
    if (time < targets[i].end_s - kWindow) q += Configuration(0.004, -0.003, 0.02, 0.02);
    return q;
  });
  const RunScore run = ScoreRun("closed_loop", targets, truth, kRest, kWindow);
  EXPECT_EQ(run.targets_scored, 5);
  EXPECT_NEAR(run.max_tip_error_mm, 0.0, 1e-9);
  // A longer window takes in the settling, which is far off.
  const RunScore longer = ScoreRun("closed_loop", targets, truth, kRest, kWindow + 0.5);
  EXPECT_GT(longer.mean_tip_error_mm, 1.0);
  // A window longer than the hold is the whole hold.
  const RunScore whole = ScoreRun("closed_loop", targets, truth, kRest, 100.0);
  for (const TargetScore& t : whole.targets) {
    EXPECT_EQ(t.samples, SamplesIn(truth, targets[t.index].start_s, targets[t.index].end_s));
  }
}

TEST(ClosedLoopScore, TargetsWithoutSamplesAreLeftOut) {
  std::mt19937 random(4);
  const std::vector<ExperimentTarget> targets = SomeTargets(6);
  std::vector<Configuration> seen;
  for (size_t i = 0; i < targets.size(); ++i) seen.push_back(RandomConfiguration(random));
  auto truth = TruthStream(targets, [&](size_t i, double) { return seen[i]; });
  // The rig went quiet during target 2's window (index 2).
  std::erase_if(truth, [&](const ConfigurationSample& s) {
    return s.time_s >= targets[2].end_s - kWindow && s.time_s < targets[2].end_s;
  });
  std::shuffle(truth.begin(), truth.end(), random);  // order does not matter
  const RunScore run = ScoreRun("open_loop", targets, truth, kRest, kWindow);
  EXPECT_EQ(run.targets[2].samples, 0);
  EXPECT_EQ(run.targets_scored, 5);
  double sum = 0.0;
  int within = 0;
  for (const TargetScore& t : run.targets) {
    if (t.index == 2) continue;
    const double expected = (IndependentTip(seen[t.index]) - t.target_tip).norm();
    EXPECT_NEAR(t.tip_error_mm, expected, 1e-9);
    sum += expected;
    within += expected <= 20.0 ? 1 : 0;
  }
  EXPECT_NEAR(run.mean_tip_error_mm, sum / 5, 1e-9);
  EXPECT_EQ(run.targets_within(20.0), within);
  EXPECT_EQ(run.targets_within(1e9), 5);

  const RunScore empty = ScoreRun("open_loop", targets, {}, kRest, kWindow);
  EXPECT_EQ(empty.targets_scored, 0);
  EXPECT_EQ(empty.mean_tip_error_mm, 0.0);
}

TEST(ClosedLoopScore, TipPathIsInTimeOrder) {
  std::mt19937 random(5);
  std::vector<ConfigurationSample> truth;
  truth.reserve(40);
  for (int k = 0; k < 40; ++k) truth.push_back({k / kRate, RandomConfiguration(random)});
  std::vector<ConfigurationSample> shuffled = truth;
  std::shuffle(shuffled.begin(), shuffled.end(), random);
  const std::vector<Vec3> path = TipPath(shuffled, kRest);
  ASSERT_EQ(path.size(), truth.size());
  for (size_t k = 0; k < truth.size(); ++k) {
    EXPECT_LT((path[k] - IndependentTip(truth[k].q)).norm(), 1e-9);
  }
}

std::vector<RunScore> TwoRuns(const std::vector<ExperimentTarget>& targets,
                              std::vector<std::vector<ConfigurationSample>>* truths = nullptr) {
  std::mt19937 random(6);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<RunScore> runs;
  for (const auto& [mode, size] : {std::pair{"open_loop", 5e-4}, std::pair{"closed_loop", 2e-5}}) {
    // A copy: a lambda may not capture a structured binding before C++20.
    const auto truth = TruthStream(targets, [&, size = size](size_t i, double) {
      return Configuration(targets[i].q +
                           size * Configuration(noise(random), noise(random), 0.0, 0.0));
    });
    runs.push_back(ScoreRun(mode, targets, truth, kRest, kWindow));
    if (truths != nullptr) truths->push_back(truth);
  }
  return runs;
}

TEST(ClosedLoopScore, TableHasEveryTargetAndTheMeans) {
  const std::vector<ExperimentTarget> targets = SomeTargets(12);
  const std::vector<RunScore> runs = TwoRuns(targets);
  const std::string table = FormatExperimentTable(targets, runs, kRest);
  std::istringstream lines(table);
  std::string line;
  std::vector<int> indices;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    int index = 0;
    if (fields >> index && index > 0) indices.push_back(index);
  }
  std::vector<int> expected(12);
  std::iota(expected.begin(), expected.end(), 1);
  EXPECT_EQ(indices, expected) << table;
  for (const RunScore& run : runs) {
    std::ostringstream mean;
    mean << "mean " << std::fixed << std::setprecision(3) << run.mean_tip_error_mm << " mm";
    EXPECT_NE(table.find(run.mode + ": " + mean.str()), std::string::npos) << table;
    EXPECT_NE(table.find(std::to_string(run.targets_within(1.0)) + "/12 within 1 mm"),
              std::string::npos)
        << table;
  }
  EXPECT_NE(table.find("1/m"), std::string::npos);
}

double BendAngle(const Configuration& q) {
  return std::hypot(q(kKappaX), q(kKappaZ)) * kRest.distal;
}

double TourLength(const std::vector<Vec3>& tips) {
  double length = 0.0;
  for (size_t i = 1; i < tips.size(); ++i) length += (tips[i] - tips[i - 1]).norm();
  return length;
}

TEST(ExperimentTargets, SpreadWithinTheBendLimitAsAShortTour) {
  std::mt19937 random(7);
  for (uint32_t seed = 1; seed <= 10; ++seed) {
    ExperimentTargetOptions options;
    options.seed = seed;
    const std::vector<ExperimentTarget> targets = MakeExperimentTargets(options, kRest);
    ASSERT_EQ(targets.size(), 20u);
    std::array<int, 4> quadrants{};
    double largest = 0.0;
    std::vector<Vec3> tips;
    for (size_t i = 0; i < targets.size(); ++i) {
      const ExperimentTarget& t = targets[i];
      EXPECT_NEAR(t.start_s, options.first_start_s + i * options.hold_s, 1e-9);
      EXPECT_NEAR(t.end_s - t.start_s, options.hold_s, 1e-9);
      if (i > 0) {
        EXPECT_EQ(t.start_s, targets[i - 1].end_s);
      }
      EXPECT_LE(BendAngle(t.q), options.max_bend_angle + 1e-12);
      EXPECT_EQ(t.q(kStrainProximal), 0.0);
      EXPECT_EQ(t.q(kStrainDistal), options.eps1);
      largest = std::max(largest, BendAngle(t.q));
      ++quadrants[(t.q(kKappaX) >= 0 ? 0 : 1) + (t.q(kKappaZ) >= 0 ? 0 : 2)];
      tips.push_back(IndependentTip(t.q));
    }
    EXPECT_GT(largest, 0.9 * options.max_bend_angle);  // reaches out to the limit
    for (int count : quadrants) EXPECT_GE(count, 3) << "seed " << seed;
    // Shorter than random orders of the same targets, on average by far.
    double random_length = 0.0;
    for (int trial = 0; trial < 50; ++trial) {
      std::shuffle(tips.begin() + 1, tips.end(), random);
      random_length += TourLength(tips) / 50;
    }
    std::vector<Vec3> ordered;
    ordered.reserve(targets.size());
    for (const ExperimentTarget& t : targets) ordered.push_back(IndependentTip(t.q));
    EXPECT_LT(TourLength(ordered), 0.5 * random_length) << "seed " << seed;
  }
}

TEST(ExperimentTargets, SeedDecidesAndOptionsAreChecked) {
  ExperimentTargetOptions options;
  const auto a = MakeExperimentTargets(options, kRest);
  const auto b = MakeExperimentTargets(options, kRest);
  options.seed += 1;
  const auto c = MakeExperimentTargets(options, kRest);
  EXPECT_EQ(a[5].q, b[5].q);
  EXPECT_NE(a[5].q, c[5].q);
  options.count = 1;
  EXPECT_EQ(MakeExperimentTargets(options, kRest).size(), 1u);
  for (const auto& spoil : std::vector<std::function<void(ExperimentTargetOptions&)>>{
           [](auto& o) { o.count = 0; }, [](auto& o) { o.hold_s = 0.0; },
           [](auto& o) { o.max_bend_angle = 4.0; }, [](auto& o) { o.eps1 = -0.1; },
           [](auto& o) { o.first_start_s = std::nan(""); }}) {
    ExperimentTargetOptions bad;
    spoil(bad);
    EXPECT_NE(bad.Validate(), "");
    EXPECT_THROW(MakeExperimentTargets(bad, kRest), std::invalid_argument);
  }
  EXPECT_EQ(ExperimentTargetOptions().Validate(), "");
}

int DifferingPixels(const cv::Mat& a, const cv::Mat& b, const cv::Rect& region) {
  cv::Mat difference;
  cv::absdiff(a(region), b(region), difference);
  cv::Mat gray;
  cv::cvtColor(difference, gray, cv::COLOR_BGR2GRAY);
  return cv::countNonZero(gray);
}

TEST(ExperimentPlot, EachRunIsDrawnInBothPanels) {
  const std::vector<ExperimentTarget> targets = SomeTargets(20);
  std::vector<std::vector<ConfigurationSample>> truths;
  const std::vector<RunScore> scores = TwoRuns(targets, &truths);
  std::vector<ExperimentPlotRun> runs;
  for (size_t r = 0; r < 2; ++r)
    runs.push_back({scores[r].mode, TipPath(truths[r], kRest), &scores[r]});
  const cv::Mat both = DrawExperimentPlot(targets, runs, kRest);
  const cv::Mat one = DrawExperimentPlot(targets, {runs[0]}, kRest);
  ASSERT_EQ(both.size(), cv::Size(1400, 700));
  ASSERT_EQ(both.type(), CV_8UC3);
  const cv::Mat white(both.size(), CV_8UC3, cv::Scalar::all(255));
  EXPECT_GT(DifferingPixels(both, white, cv::Rect(0, 0, 1400, 700)), 10000);
  // The second run's path, legend and bars show on both panels (below the title).
  EXPECT_GT(DifferingPixels(both, one, cv::Rect(0, 40, 700, 660)), 200);
  EXPECT_GT(DifferingPixels(both, one, cv::Rect(700, 40, 700, 660)), 200);
  // A different path moves the picture.
  runs[1].tip_path = TipPath(truths[0], kRest);
  EXPECT_GT(
      DifferingPixels(both, DrawExperimentPlot(targets, runs, kRest), cv::Rect(0, 40, 700, 660)),
      100);
}

TEST(ExperimentPlot, DegenerateInputsStillDraw) {
  const std::vector<ExperimentTarget> targets = SomeTargets(3);
  RunScore unscored = ScoreRun("open_loop", targets, {}, kRest, kWindow);
  for (const cv::Mat& plot :
       {DrawExperimentPlot({}, {}, kRest), DrawExperimentPlot(targets, {}, kRest),
        DrawExperimentPlot(targets, {{"open_loop", {}, &unscored}}, kRest),
        DrawExperimentPlot(targets, {{"closed_loop", {Vec3(0, 760, 0)}, nullptr}}, kRest)}) {
    EXPECT_EQ(plot.size(), cv::Size(1400, 700));
  }
}

}  // namespace
}  // namespace shapesense
