#pragma once

// What the live demo found, as it prints it and as report.json.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "clients/tools/demo/demo_scorer.h"
#include "clients/tools/demo/replay_check.h"
#include "runtime/process/process_group.h"

namespace shapesense {

struct LiveDemoReport {
  std::string network;  // "private network namespace" or why not
  std::string cameras;  // CameraSourceName
  std::string lcm_url;
  double rate_hz = 0.0;
  double duration_s = 0.0;  // asked for
  double measured_s = 0.0;  // from the capture service's start to its stop
  DemoScore score;
  ReplayCheck replay;
  std::filesystem::path log;
  int64_t log_bytes = 0;
  std::vector<ProgramEnd> programs;
  std::string failure;  // a program that failed, with its last output; "" when none
  bool interrupted = false;
};

// One line of progress: time, frame-sets, losses, accuracy and latency so far.
std::string ProgressLine(const LiveScorer::Report& report, double elapsed_s, double duration_s);

void PrintLiveSummary(const LiveDemoReport& report, std::ostream& out);
void PrintReplayCheck(const ReplayCheck& check, std::ostream& out);

nlohmann::json LiveReportToJson(const LiveDemoReport& report);
// How each program ran and ended: [{name, ended, clean, argv}], for the reports.
nlohmann::json ProgramsToJson(const std::vector<ProgramEnd>& programs);
// What produced a report: the project's version and the time (UTC).
nlohmann::json ProvenanceToJson();

}  // namespace shapesense
