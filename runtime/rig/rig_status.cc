#include "runtime/rig/rig_status.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

namespace shapesense {
namespace {

// The largest offset of another host's clock, ms (0 when none heard).
double LargestOffsetMs(const service_status_t& status) {
  double largest = 0.0;
  for (const int64_t offset : status.clock_offsets_us) {
    const double ms = static_cast<double>(offset) * 1e-3;
    if (std::abs(ms) > std::abs(largest)) largest = ms;
  }
  return largest;
}

std::string Cell(const char* format, double value) {
  char text[32];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

std::string Shortened(const std::string& text, size_t width) {
  return text.size() <= width ? text : text.substr(0, width - 3) + "...";
}

}  // namespace

const char* ProgramStateName(ProgramState state) {
  switch (state) {
    case ProgramState::kUp:
      return "up";
    case ProgramState::kStale:
      return "stale";
    case ProgramState::kMissing:
      return "missing";
    case ProgramState::kUnexpected:
      return "unexpected";
  }
  return "?";
}

std::string StatusServiceOf(const std::string& program) {
  if (program == "rig-sim") return "rig_sim";
  static const std::set<std::string> with_status = {"capture", "carving", "shape", "controller",
                                                    "monitor"};
  return with_status.count(program) > 0 ? program : "";
}

RigStatusBoard::RigStatusBoard(std::optional<RigFile> rig, double stale_after_s,
                               double missing_after_s, bool expect_heard)
    : rig_(std::move(rig)),
      stale_after_s_(stale_after_s),
      missing_after_s_(missing_after_s),
      expect_heard_(expect_heard) {}

void RigStatusBoard::Observe(const service_status_t& status, int64_t receive_utime) {
  heard_[{status.host, status.service}] = {status, receive_utime};
}

void RigStatusBoard::Observe(const shape_t& shape) {
  stages_.clear();
  for (const stage_time_t& stage : shape.stage_times) {
    stages_.emplace_back(stage.stage, static_cast<double>(stage.duration_us) * 1e-3);
  }
}

std::vector<RigStatusRow> RigStatusBoard::Rows(int64_t now_utime) const {
  std::vector<RigStatusRow> rows;
  std::set<std::pair<std::string, std::string>> expected;
  for (const RigHost& host : rig_ ? rig_->hosts : std::vector<RigHost>{}) {
    for (const RigProgram& program : host.programs) {
      const std::string service = StatusServiceOf(program.program);
      if (!service.empty()) expected.insert({host.name, service});
    }
  }
  rows.reserve(expected.size() + heard_.size());
  for (const auto& key : expected) {
    rows.push_back({key.first, key.second, ProgramState::kMissing, std::nullopt, 0.0});
  }
  for (const auto& [key, heard] : heard_) {
    if (expected.count(key) == 0) {
      const bool expected_once_heard = expect_heard_ && !rig_;
      rows.push_back({key.first, key.second,
                      expected_once_heard ? ProgramState::kUp : ProgramState::kUnexpected,
                      std::nullopt, 0.0});
    }
  }
  for (RigStatusRow& row : rows) {
    const auto found = heard_.find({row.host, row.service});
    if (found == heard_.end()) continue;
    row.last = found->second.status;
    row.status_age_s = static_cast<double>(now_utime - found->second.receive_utime) * 1e-6;
    if (row.status_age_s > missing_after_s_) {
      row.state = ProgramState::kMissing;
    } else if (row.state != ProgramState::kUnexpected) {
      row.state = row.status_age_s > stale_after_s_ ? ProgramState::kStale : ProgramState::kUp;
    }
  }
  return rows;
}

bool RigStatusBoard::Complete(int64_t now_utime) const {
  const std::vector<RigStatusRow> rows = Rows(now_utime);
  return std::none_of(rows.begin(), rows.end(), [](const RigStatusRow& row) {
    return row.state == ProgramState::kMissing || row.state == ProgramState::kStale;
  });
}

std::string RigStatusBoard::Table(int64_t now_utime) const {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof(line), "%-10s %-11s %-10s %7s %8s %7s %7s %6s %5s %6s %7s %9s  %s\n",
                "HOST", "PROGRAM", "STATE", "PID", "UPTIME", "IN/s", "OUT/s", "DROPS", "QUEUE",
                "CPU%", "RSS MB", "CLOCK ms", "LAST ERROR");
  out << line;
  for (const RigStatusRow& row : Rows(now_utime)) {
    if (!row.last) {
      std::snprintf(line, sizeof(line), "%-10s %-11s %-10s\n", row.host.c_str(),
                    row.service.c_str(), ProgramStateName(row.state));
      out << line;
      continue;
    }
    const service_status_t& s = *row.last;
    std::snprintf(line, sizeof(line),
                  "%-10s %-11s %-10s %7d %8s %7.1f %7.1f %6lld %5d %6.1f %7.1f %9s  %s\n",
                  row.host.c_str(), row.service.c_str(), ProgramStateName(row.state), s.pid,
                  Cell("%.0fs", s.uptime_s).c_str(), s.input_rate_hz, s.output_rate_hz,
                  static_cast<long long>(s.dropped), s.queue_depth, s.cpu_percent,
                  static_cast<double>(s.rss_bytes) / 1e6, Cell("%+.3f", LargestOffsetMs(s)).c_str(),
                  Shortened(s.last_error, 60).c_str());
    out << line;
  }
  if (!stages_.empty()) {
    out << "last shape's stages, ms:";
    for (const auto& [stage, ms] : stages_) out << ' ' << stage << ' ' << Cell("%.2f", ms);
    out << '\n';
  }
  return out.str();
}

std::string RigStatusBoard::Json(int64_t now_utime) const {
  nlohmann::json rows = nlohmann::json::array();
  for (const RigStatusRow& row : Rows(now_utime)) {
    nlohmann::json item = {
        {"host", row.host}, {"program", row.service}, {"state", ProgramStateName(row.state)}};
    if (row.last) {
      const service_status_t& s = *row.last;
      nlohmann::json offsets = nlohmann::json::object();
      for (size_t i = 0; i < s.clock_offset_hosts.size(); ++i) {
        offsets[s.clock_offset_hosts[i]] = static_cast<double>(s.clock_offsets_us[i]) * 1e-3;
      }
      item.update({{"pid", s.pid},
                   {"uptime_s", s.uptime_s},
                   {"status_age_s", row.status_age_s},
                   {"input_rate_hz", s.input_rate_hz},
                   {"output_rate_hz", s.output_rate_hz},
                   {"received", s.received},
                   {"published", s.published},
                   {"dropped", s.dropped},
                   {"rejected", s.rejected},
                   {"errors", s.errors},
                   {"queue_depth", s.queue_depth},
                   {"cpu_percent", s.cpu_percent},
                   {"rss_bytes", s.rss_bytes},
                   {"clock_offsets_ms", offsets},
                   {"clock_warning", s.clock_warning},
                   {"auth", s.auth},
                   {"last_error", s.last_error}});
    }
    rows.push_back(item);
  }
  nlohmann::json stages = nlohmann::json::object();
  for (const auto& [stage, ms] : stages_) stages[stage] = ms;
  return nlohmann::json{
      {"programs", rows}, {"stage_latency_ms", stages}, {"complete", Complete(now_utime)}}
      .dump(2);
}

}  // namespace shapesense
