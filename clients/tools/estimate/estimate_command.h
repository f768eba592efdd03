#pragma once

// `shapesense estimate --model manipulator.yaml --data poses.csv [--tensions]
//                      [--out result.json] [--plot shapes.png]`
//
// Estimates the manipulator's stiffnesses from sensed poses (pose_csv.h) three
// ways (tensionless least squares, output-error fit, and from tensions with
// --tensions), prints them with their standard deviations, the tip-error
// table and the identifiability warnings, and writes the result as JSON and a
// plot of sensed against model shapes. The estimate written as "stiffness" is
// the output-error fit's, or the tension-based one's with --tensions.

#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

namespace shapesense {

struct EstimateArgs {
  std::string model_path;  // manipulator YAML (config/manipulator.yaml)
  std::string data_path;   // pose CSV
  bool use_tensions = false;
  std::string out_path;           // JSON; empty: print only
  std::string plot_path;          // PNG; empty: out_path with .png, or none without --out
  double max_relative_std = 0.1;  // warn above this relative standard deviation
};

// Exit code: 0 done; 1 bad input or an output that cannot be written (the
// message on `log` names the file, line or key; nothing is written); 2 the
// estimation failed.
int RunEstimate(const EstimateArgs& args, std::ostream& log);

// Registers the `estimate` subcommand; its callback runs RunEstimate on
// std::cout and turns a non-zero exit code into CLI::RuntimeError.
void AddEstimateCommand(CLI::App& app);

}  // namespace shapesense
