#include "clients/tools/demo/demo_report.h"

#include <iomanip>
#include <sstream>

#include "clients/tools/monitor/monitor_command.h"
#include "runtime/provenance.h"

namespace shapesense {
namespace {

// The stages in the order a frame-set goes through them; others after.
std::vector<std::string> StagesInOrder(const LiveScorer::Report& report) {
  std::vector<std::string> stages;
  for (const char* stage : {"capture", "transport", "silhouette", "carving", "shape"}) {
    if (report.stage_ms.contains(stage)) stages.push_back(stage);
  }
  for (const auto& [stage, p] : report.stage_ms) {
    if (std::find(stages.begin(), stages.end(), stage) == stages.end()) stages.push_back(stage);
  }
  return stages;
}

double PerSecond(int count, double seconds) {
  return seconds > 0.0 ? static_cast<double>(count) / seconds : 0.0;
}

void PrintFrameSets(const LiveDemoReport& r, std::ostream& out) {
  const LiveScorer::Report& s = r.score.live;
  out << std::fixed << std::setprecision(1) << "frame-sets: " << s.truths << " rendered ("
      << PerSecond(s.truths, r.measured_s) << "/s), " << s.valid_shapes << " measured ("
      << PerSecond(s.valid_shapes, r.measured_s) << "/s), " << s.matched
      << " paired with their truth; lost " << s.unmatched_truths << ", invalid "
      << s.shapes - s.valid_shapes << "\n";
}

void PrintAccuracy(const DemoScore& score, std::ostream& out) {
  const LiveScorer::Report& s = score.live;
  const ShapeErrorSummary& e = score.errors;
  out << std::fixed << std::setprecision(3) << "accuracy against the truth over " << s.matched
      << " frame-sets (mean / max):\n"
      << "  centreline RMS   " << s.centerline_rms_mean << " / " << s.centerline_rms_max << " mm\n"
      << "  tip              " << s.tip_error_mean << " / " << s.tip_error_max << " mm\n"
      << "  tape centres     " << e.mean.marker_rms << " / " << e.max.marker_max << " mm ("
      << e.mean.markers_found << " of " << e.mean.markers_expected << " tapes found)\n";
}

void PrintLatency(const LiveScorer::Report& s, std::ostream& out) {
  out << "latency, ms          p50      p99      max\n" << std::fixed << std::setprecision(2);
  auto row = [&out](const std::string& name, const LiveScorer::Percentiles& p) {
    out << "  " << std::left << std::setw(16) << name << std::right << std::setw(9) << p.p50
        << std::setw(9) << p.p99 << std::setw(9) << p.max << "\n";
  };
  for (const std::string& stage : StagesInOrder(s)) row(stage, s.stage_ms.at(stage));
  row("trigger -> shape", s.trigger_to_shape_ms);
}

void PrintServices(const LiveScorer::Report& s, std::ostream& out) {
  for (const auto& [service, status] : s.last_status) {
    out << "  " << std::left << std::setw(8) << service << std::right << " received "
        << status.received << ", published " << status.published << ", dropped " << status.dropped
        << ", rejected " << status.rejected << ", errors " << status.errors
        << (status.last_error.empty() ? "" : " (last: " + status.last_error + ")") << "\n";
  }
}

nlohmann::json Percentiles(const LiveScorer::Percentiles& p) {
  return {{"p50", p.p50}, {"p99", p.p99}, {"max", p.max}, {"count", p.count}};
}

nlohmann::json AccuracyToJson(const DemoScore& score) {
  const LiveScorer::Report& s = score.live;
  const ShapeErrorSummary& e = score.errors;
  return {{"frame_sets", s.matched},
          {"centerline_rms", {{"mean", s.centerline_rms_mean}, {"max", s.centerline_rms_max}}},
          {"tip", {{"mean", s.tip_error_mean}, {"max", s.tip_error_max}}},
          {"tapes",
           {{"rms_mean", e.mean.marker_rms},
            {"max", e.max.marker_max},
            {"found", e.mean.markers_found},  // over all frame-sets
            {"expected", e.mean.markers_expected}}},
          {"coverage_rms", {{"mean", e.mean.coverage_rms}, {"max", e.max.coverage_rms}}}};
}

nlohmann::json LatencyToJson(const LiveScorer::Report& s) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [stage, p] : s.stage_ms) out[stage] = Percentiles(p);
  out["trigger_to_shape"] = Percentiles(s.trigger_to_shape_ms);
  return out;
}

nlohmann::json ReplayToJson(const ReplayCheck& c) {
  return {{"ran", c.ran},
          {"error", c.error},
          {"compared", c.compared},
          {"identical", c.identical},
          {"max_difference_mm", c.max_difference_mm},
          {"live_only", c.live_only},
          {"replay_only", c.replay_only}};
}

}  // namespace

nlohmann::json ProvenanceToJson() { return {{"version", ProjectVersion()}, {"written", UtcNow()}}; }

nlohmann::json ProgramsToJson(const std::vector<ProgramEnd>& programs) {
  nlohmann::json out = nlohmann::json::array();
  for (const ProgramEnd& end : programs) {
    out.push_back(
        {{"name", end.name}, {"ended", end.how}, {"clean", end.clean}, {"argv", end.argv}});
  }
  return out;
}

std::string ProgressLine(const LiveScorer::Report& s, double elapsed_s, double duration_s) {
  std::ostringstream line;
  line << std::fixed << std::setprecision(1) << std::setw(5) << elapsed_s << " / " << duration_s
       << " s  frame-sets " << s.valid_shapes << " measured ("
       << PerSecond(s.valid_shapes, elapsed_s) << "/s), " << s.unmatched_truths
       << " lost  centreline RMS " << std::setprecision(3) << s.centerline_rms_mean
       << " mm  trigger->shape p50 " << std::setprecision(0) << s.trigger_to_shape_ms.p50 << " ms";
  return line.str();
}

void PrintLiveSummary(const LiveDemoReport& r, std::ostream& out) {
  out << std::fixed << std::setprecision(1) << "\nlive pipeline: " << r.measured_s
      << " s on the virtual rig, cameras: " << r.cameras << ", trigger " << r.rate_hz
      << " Hz, network: " << r.network << (r.interrupted ? " (interrupted)" : "") << "\n";
  PrintFrameSets(r, out);
  PrintAccuracy(r.score, out);
  PrintLatency(r.score.live, out);
  out << "services (last status):\n";
  PrintServices(r.score.live, out);
  out << std::setprecision(0) << "log: " << r.log.string() << " ("
      << static_cast<double>(r.log_bytes) / 1e6 << " MB)\n";
}

void PrintReplayCheck(const ReplayCheck& c, std::ostream& out) {
  if (!c.ran) {
    out << "replay: not run" << (c.error.empty() ? "" : ": " + c.error) << "\n";
    return;
  }
  out << "replay: " << c.compared << " frame-sets measured both live and from the log; "
      << (c.identical == c.compared ? "all" : std::to_string(c.identical) + " of them")
      << " identical (largest difference " << std::scientific << std::setprecision(1)
      << c.max_difference_mm << std::fixed << " mm)";
  if (c.live_only + c.replay_only > 0) {
    out << "; " << c.live_only << " only live (incomplete in the log), " << c.replay_only
        << " only in the replay (dropped live)";
  }
  out << "\n";
}

nlohmann::json LiveReportToJson(const LiveDemoReport& r) {
  const LiveScorer::Report& s = r.score.live;
  return {{"provenance", ProvenanceToJson()},
          {"run",
           {{"network", r.network},
            {"cameras", r.cameras},
            {"lcm_url", r.lcm_url},
            {"rate_hz", r.rate_hz},
            {"duration_s", r.duration_s},
            {"measured_s", r.measured_s},
            {"interrupted", r.interrupted}}},
          {"frame_sets",
           {{"rendered", s.truths},
            {"measured", s.valid_shapes},
            {"matched", s.matched},
            {"lost", s.unmatched_truths},
            {"invalid", s.shapes - s.valid_shapes},
            {"measured_per_s", PerSecond(s.valid_shapes, r.measured_s)}}},
          {"accuracy_mm", AccuracyToJson(r.score)},
          {"latency_ms", LatencyToJson(s)},
          {"monitor", ReportToJson(s)},
          {"replay", ReplayToJson(r.replay)},
          {"log", {{"path", r.log.string()}, {"bytes", r.log_bytes}}},
          {"programs", ProgramsToJson(r.programs)},
          {"failed", r.failure}};
}

}  // namespace shapesense
