#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "clients/tools/monitor/live_scorer.h"

namespace shapesense {

struct MonitorArgs {
  std::string lcm_url;           // empty: LCM's default
  double duration_s = 10.0;      // listen this long
  std::filesystem::path report;  // JSON report; empty: none
};

// Listens to the shapes, the virtual rig's truth and the services' status for
// a bounded time, then prints (and writes) accuracy, losses and latency.
LiveScorer::Report RunMonitor(const MonitorArgs& args, const std::atomic<bool>& stop,
                              std::ostream& log);

nlohmann::json ReportToJson(const LiveScorer::Report& report);
void PrintReport(const LiveScorer::Report& report, std::ostream& out);

// Registers `shapesense monitor`.
void AddMonitorCommand(CLI::App& app);

}  // namespace shapesense
