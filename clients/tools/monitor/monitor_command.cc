#include "clients/tools/monitor/monitor_command.h"

#include <chrono>
#include <iomanip>
#include <iostream>

#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"

namespace shapesense {
namespace {

nlohmann::json PercentilesToJson(const LiveScorer::Percentiles& p) {
  return {{"p50", p.p50}, {"p99", p.p99}, {"max", p.max}, {"count", p.count}};
}

nlohmann::json StatusToJson(const service_status_t& s) {
  return {{"host", s.host},
          {"received", s.received},
          {"published", s.published},
          {"dropped", s.dropped},
          {"rejected", s.rejected},
          {"errors", s.errors},
          {"queue_depth", s.queue_depth},
          {"last_error", s.last_error}};
}

void Subscribe(LcmBus& bus, LiveScorer& scorer) {
  bus.Subscribe<shape_t>(channels::kShape,
                         [&scorer](const shape_t& shape, const std::string&, int64_t utime) {
                           scorer.AddShape(shape, utime);
                         });
  bus.Subscribe<shape_t>(channels::kTruth, [&scorer](const shape_t& truth, const std::string&,
                                                     int64_t) { scorer.AddTruth(truth); });
  bus.Subscribe<service_status_t>(channels::kStatusPattern,
                                  [&scorer](const service_status_t& status, const std::string&,
                                            int64_t) { scorer.AddStatus(status); });
}

}  // namespace

nlohmann::json ReportToJson(const LiveScorer::Report& r) {
  nlohmann::json stages = nlohmann::json::object();
  for (const auto& [stage, p] : r.stage_ms) stages[stage] = PercentilesToJson(p);
  nlohmann::json status = nlohmann::json::object();
  for (const auto& [service, s] : r.last_status) status[service] = StatusToJson(s);
  return {{"truth_frame_sets", r.truths},
          {"shapes", r.shapes},
          {"valid_shapes", r.valid_shapes},
          {"matched", r.matched},
          {"unmatched_truths", r.unmatched_truths},
          {"centerline_rms_mm", {{"mean", r.centerline_rms_mean}, {"max", r.centerline_rms_max}}},
          {"tip_error_mm", {{"mean", r.tip_error_mean}, {"max", r.tip_error_max}}},
          {"stage_ms", stages},
          {"trigger_to_shape_ms", PercentilesToJson(r.trigger_to_shape_ms)},
          {"services", status}};
}

void PrintReport(const LiveScorer::Report& r, std::ostream& out) {
  out << std::fixed << std::setprecision(3) << "frame-sets rendered " << r.truths << ", shapes "
      << r.shapes << " (" << r.valid_shapes << " valid, " << r.matched
      << " matched to the truth), lost " << r.unmatched_truths << "\n"
      << "centreline RMS " << r.centerline_rms_mean << " mm mean, " << r.centerline_rms_max
      << " mm max; tip " << r.tip_error_mean << " mm mean, " << r.tip_error_max << " mm max\n"
      << "latency, ms (p50 / p99 / max):\n";
  for (const auto& [stage, p] : r.stage_ms) {
    out << "  " << std::left << std::setw(18) << stage << std::right << std::setw(8) << p.p50
        << std::setw(9) << p.p99 << std::setw(9) << p.max << "\n";
  }
  const LiveScorer::Percentiles& e = r.trigger_to_shape_ms;
  out << "  " << std::left << std::setw(18) << "trigger -> shape" << std::right << std::setw(8)
      << e.p50 << std::setw(9) << e.p99 << std::setw(9) << e.max << "\n";
  for (const auto& [service, s] : r.last_status) {
    out << "service " << service << " on " << s.host << ": received " << s.received
        << ", published " << s.published << ", dropped " << s.dropped << ", rejected " << s.rejected
        << ", errors " << s.errors << (s.last_error.empty() ? "" : " (last: " + s.last_error + ")")
        << "\n";
  }
}

LiveScorer::Report RunMonitor(const MonitorArgs& args, const std::atomic<bool>& stop,
                              std::ostream& log) {
  LcmBusOptions options = LcmBusOptions::FromEnvironment(args.lcm_url);
  // It watches and acts on nothing: a workstation needs no key to run it
  // (with one, it verifies as any program).
  options.auth.read_only = true;
  LcmBus bus(options);
  LiveScorer scorer;
  Subscribe(bus, scorer);
  const auto end =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(args.duration_s);
  while (!stop && std::chrono::steady_clock::now() < end) bus.Handle(50);
  LiveScorer::Report report = scorer.Finish(NowUtime());
  PrintReport(report, log);
  if (!args.report.empty()) WriteFileAtomically(args.report, ReportToJson(report).dump(2) + "\n");
  return report;
}

void AddMonitorCommand(CLI::App& app) {
  auto args = std::make_shared<MonitorArgs>();
  CLI::App* command = app.add_subcommand(
      "monitor",
      "Listen to shapes, the virtual rig's truth and service status; report accuracy and latency");
  command->add_option("--lcm-url", args->lcm_url, "LCM provider URL (default: LCM's default)");
  command->add_option("--duration", args->duration_s, "seconds to listen")->capture_default_str();
  command->add_option("--report", args->report, "write the report as JSON here");
  command->callback([args] {
    static const std::atomic<bool> never_stop{false};
    RunMonitor(*args, never_stop, std::cout);
  });
}

}  // namespace shapesense
