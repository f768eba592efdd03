#include "libs/evaluation/closed_loop_score.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>

#include "libs/core/error.h"
#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string Fixed(double value, int width, int precision) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(precision) << std::setw(width) << value;
  return out.str();
}

std::string PadLeft(const std::string& text, int width) {
  const size_t size = static_cast<size_t>(std::max(width, 0));
  return text.size() >= size ? text : std::string(size - text.size(), ' ') + text;
}

// The tip, and the tip seen from the distal section's start (so eps0, which
// only slides the distal section along the shaft, drops out).
struct TipPoints {
  Vec3 tip;
  Vec3 distal;
};

TipPoints TipPointsOf(const Configuration& q, const SectionLengths& rest) {
  const Vec3 tip = BaseFromTip(q, rest).translation();
  return {tip, tip - BaseFromDistalStart(q, rest).translation()};
}

TargetScore ScoreTarget(int index, const ExperimentTarget& target,
                        const std::vector<ConfigurationSample>& truth, const SectionLengths& rest,
                        double window_s) {
  TargetScore score;
  score.index = index;
  score.target_q = target.q;
  const TipPoints wanted = TipPointsOf(target.q, rest);
  score.target_tip = wanted.tip;
  const double window_start = std::max(target.start_s, target.end_s - window_s);
  Vec3 tip_sum = Vec3::Zero();
  for (const ConfigurationSample& sample : truth) {
    if (sample.time_s < window_start || sample.time_s >= target.end_s) continue;
    const TipPoints seen = TipPointsOf(sample.q, rest);
    const double error = (seen.tip - wanted.tip).norm();
    tip_sum += seen.tip;
    score.tip_error_mm += error;
    score.max_tip_error_mm = std::max(score.max_tip_error_mm, error);
    score.distal_tip_error_mm += (seen.distal - wanted.distal).norm();
    ++score.samples;
  }
  if (score.samples > 0) {
    score.mean_tip = tip_sum / score.samples;
    score.tip_error_mm /= score.samples;
    score.distal_tip_error_mm /= score.samples;
  }
  return score;
}

void Summarize(RunScore& run, const SectionLengths& rest) {
  double sum = 0.0;
  for (const TargetScore& target : run.targets) {
    if (target.samples == 0) continue;
    ++run.targets_scored;
    sum += target.tip_error_mm;
    run.max_tip_error_mm = std::max(run.max_tip_error_mm, target.tip_error_mm);
  }
  if (run.targets_scored == 0) return;
  run.mean_tip_error_mm = sum / run.targets_scored;
  if (rest.distal > 0.0) run.mean_tip_error_percent = run.mean_tip_error_mm / rest.distal * 100.0;
}

// ---- the table ----

int RunColumnWidth(const RunScore& run) {
  return std::max(12, static_cast<int>(run.mode.size()) + 2);
}

std::string TableHeader(const std::vector<RunScore>& runs) {
  std::string names = "  #  kappa_x  kappa_z    tip_x    tip_y    tip_z |";
  std::string units = "       (1/m)    (1/m)     (mm)     (mm)     (mm) |";
  for (const RunScore& run : runs) {
    names += PadLeft(run.mode, RunColumnWidth(run));
    units += PadLeft("error (mm)", RunColumnWidth(run));
  }
  return names + "\n" + units + "\n";
}

std::string TableRow(size_t i, const ExperimentTarget& target, const std::vector<RunScore>& runs,
                     const SectionLengths& rest) {
  const Vec3 tip = BaseFromTip(target.q, rest).translation();
  std::string row = PadLeft(std::to_string(i + 1), 3) + Fixed(target.q(kKappaX) * 1e3, 9, 3) +
                    Fixed(target.q(kKappaZ) * 1e3, 9, 3) + Fixed(tip.x(), 9, 2) +
                    Fixed(tip.y(), 9, 2) + Fixed(tip.z(), 9, 2) + " |";
  for (const RunScore& run : runs) {
    const bool scored = i < run.targets.size() && run.targets[i].samples > 0;
    row += scored ? Fixed(run.targets[i].tip_error_mm, RunColumnWidth(run), 3)
                  : PadLeft("-", RunColumnWidth(run));
  }
  return row + "\n";
}

std::string SummaryLine(const RunScore& run, const SectionLengths& rest) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << run.mode << ": mean " << run.mean_tip_error_mm
      << " mm (" << std::setprecision(2) << run.mean_tip_error_percent
      << "% of L1 = " << Number(rest.distal) << " mm), worst " << std::setprecision(3)
      << run.max_tip_error_mm << " mm, " << run.targets_within(1.0) << "/" << run.targets_scored
      << " within 1 mm, " << run.targets_scored << "/" << run.targets.size() << " scored\n";
  return out.str();
}

// ---- the targets ----

// Bend vectors (theta cos phi, theta sin phi) spread evenly over the disc of
// radius max_bend_angle: a sunflower (golden-angle) pattern, each point
// jittered within its own ring of equal area, the whole turned by the seed.
std::vector<Vec2> SpreadBendVectors(const ExperimentTargetOptions& options) {
  std::mt19937 random(options.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  const double turn = 2.0 * kPi * unit(random);
  std::vector<Vec2> bends;
  for (int i = 0; i < options.count; ++i) {
    const double theta = options.max_bend_angle * std::sqrt((i + unit(random)) / options.count);
    const double phi = turn + i * golden_angle + 0.4 * (unit(random) - 0.5);
    bends.emplace_back(theta * std::cos(phi), theta * std::sin(phi));
  }
  return bends;
}

double Distance(const std::vector<Vec3>& points, size_t a, size_t b) {
  return (points[a] - points[b]).norm();
}

// Nearest-neighbour tour from `start`.
std::vector<size_t> NearestNeighbourTour(const std::vector<Vec3>& points, size_t start) {
  std::vector<size_t> tour = {start};
  std::vector<bool> visited(points.size(), false);
  visited[start] = true;
  while (tour.size() < points.size()) {
    size_t best = start;
    double best_distance = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < points.size(); ++i) {
      const double distance = Distance(points, tour.back(), i);
      if (!visited[i] && distance < best_distance) {
        best = i;
        best_distance = distance;
      }
    }
    visited[best] = true;
    tour.push_back(best);
  }
  return tour;
}

// 2-opt on an open path with a fixed start: reverses stretches while that
// shortens the path (removes crossings the greedy tour leaves).
void ShortenTour(const std::vector<Vec3>& points, std::vector<size_t>& tour) {
  const size_t n = tour.size();
  const auto d = [&](size_t a, size_t b) { return Distance(points, tour[a], tour[b]); };
  for (int pass = 0; pass < 100; ++pass) {
    bool improved = false;
    for (size_t i = 0; i + 2 < n; ++i) {
      for (size_t j = i + 2; j < n; ++j) {
        const bool last = j + 1 == n;
        const double before = d(i, i + 1) + (last ? 0.0 : d(j, j + 1));
        const double after = d(i, j) + (last ? 0.0 : d(i + 1, j + 1));
        if (after < before - 1e-9) {
          std::reverse(tour.begin() + static_cast<std::ptrdiff_t>(i + 1),
                       tour.begin() + static_cast<std::ptrdiff_t>(j + 1));
          improved = true;
        }
      }
    }
    if (!improved) return;
  }
}

}  // namespace

int RunScore::targets_within(double mm) const {
  return static_cast<int>(std::count_if(targets.begin(), targets.end(), [mm](const TargetScore& t) {
    return t.samples > 0 && t.tip_error_mm <= mm;
  }));
}

RunScore ScoreRun(const std::string& mode, const std::vector<ExperimentTarget>& targets,
                  const std::vector<ConfigurationSample>& truth, const SectionLengths& rest,
                  double window_s) {
  RunScore run;
  run.mode = mode;
  for (size_t i = 0; i < targets.size(); ++i) {
    run.targets.push_back(ScoreTarget(static_cast<int>(i), targets[i], truth, rest, window_s));
  }
  Summarize(run, rest);
  return run;
}

std::vector<Vec3> TipPath(const std::vector<ConfigurationSample>& truth,
                          const SectionLengths& rest) {
  std::vector<ConfigurationSample> ordered = truth;
  std::stable_sort(ordered.begin(), ordered.end(),
                   [](const ConfigurationSample& a, const ConfigurationSample& b) {
                     return a.time_s < b.time_s;
                   });
  std::vector<Vec3> path;
  path.reserve(ordered.size());
  for (const ConfigurationSample& sample : ordered) {
    path.push_back(BaseFromTip(sample.q, rest).translation());
  }
  return path;
}

std::string FormatExperimentTable(const std::vector<ExperimentTarget>& targets,
                                  const std::vector<RunScore>& runs, const SectionLengths& rest) {
  std::string table = TableHeader(runs);
  for (size_t i = 0; i < targets.size(); ++i) table += TableRow(i, targets[i], runs, rest);
  table += "\n";
  for (const RunScore& run : runs) table += SummaryLine(run, rest);
  return table;
}

std::string ExperimentTargetOptions::Validate() const {
  if (count < 1 || count > 1000) return "count: expected 1-1000, got " + std::to_string(count);
  for (const std::string& error :
       {ExpectWithin("hold_s", hold_s, {0.0, 1e6, true}, "a positive number"),
        ExpectWithin("first_start_s", first_start_s, {0.0, 1e6}, "a number >= 0"),
        ExpectWithin("max_bend_angle", max_bend_angle, {0.0, kPi, true}, "a number in (0, 3.14]"),
        ExpectWithin("eps1", eps1, {0.0, 0.5, false, true}, "a number in [0, 0.5)")}) {
    if (!error.empty()) return error;
  }
  return "";
}

std::vector<ExperimentTarget> MakeExperimentTargets(const ExperimentTargetOptions& options,
                                                    const SectionLengths& rest) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("experiment targets: " + error);
  }
  if (!(rest.distal > 0.0)) throw std::invalid_argument("experiment targets: L1 must be > 0");
  std::vector<Configuration> spread;
  std::vector<Vec3> tips;
  for (const Vec2& bend : SpreadBendVectors(options)) {
    spread.emplace_back(bend.x() / rest.distal, bend.y() / rest.distal, 0.0, options.eps1);
    tips.push_back(BaseFromTip(spread.back(), rest).translation());
  }
  // The greedy tour starts at the least bent target, nearest the straight pose.
  std::vector<size_t> tour = NearestNeighbourTour(tips, 0);
  ShortenTour(tips, tour);
  std::vector<ExperimentTarget> targets;
  const auto start = [&](size_t i) {
    return options.first_start_s + static_cast<double>(i) * options.hold_s;
  };
  for (size_t i = 0; i < tour.size(); ++i)
    targets.push_back({start(i), start(i + 1), spread[tour[i]]});
  return targets;
}

}  // namespace shapesense
