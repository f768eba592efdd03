#pragma once

// The closed-loop experiment's picture: where each run's true tip went
// against the targets, and each target's steady-state tip error per run.
// Drawn with OpenCV; the caller writes it (cv::imwrite to a PNG).

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/evaluation/closed_loop_score.h"

namespace shapesense {

struct ExperimentPlotRun {
  std::string mode;
  std::vector<Vec3> tip_path;       // TipPath(truth), base frame, mm
  const RunScore* score = nullptr;  // nullptr: no error bars for this run
};

// BGR, 8 bits, 1400 x 700: a title line with each run's mean error, then
//  left: the tips looking down the shaft from the base (x right, z up; y
//   runs along the shaft): the targets' tips as numbered circles 1..N, each
//   run's tip path as a polyline in its own colour, legend, mm ticks (equal
//   aspect, fitted to everything drawn);
//  right: each target's steady-state tip error, one bar per run, on a log
//   axis in mm with a dashed line at 1 mm, legend.
cv::Mat DrawExperimentPlot(const std::vector<ExperimentTarget>& targets,
                           const std::vector<ExperimentPlotRun>& runs, const SectionLengths& rest);

}  // namespace shapesense
