#pragma once

// What `shapesense rig status` shows: every expected program of every host
// (from the rig file), up, stale or missing by its 1 Hz status, with its
// process, rates, drops, queue, CPU, memory, last error and clock offsets,
// and the latency of each stage of the last shape. Fed by the command's LCM
// bus; no I/O here.
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "runtime/rig/rig_file.h"
#include "shapesense/service_status_t.hpp"
#include "shapesense/shape_t.hpp"

namespace shapesense {

enum class ProgramState { kUp, kStale, kMissing, kUnexpected };
const char* ProgramStateName(ProgramState state);

struct RigStatusRow {
  std::string host;
  std::string service;
  ProgramState state = ProgramState::kMissing;
  std::optional<service_status_t> last;  // its latest status
  double status_age_s = 0.0;             // since it arrived (this host's clock)
};

// The service name a rig program publishes its status under ("rig_sim"
// for the rig-sim; "" for those that publish none: lcm-logger, rig-status).
std::string StatusServiceOf(const std::string& program);

class RigStatusBoard {
 public:
  // `rig`: the expected programs (none: every program heard is shown as
  // unexpected, or as expected with `expect_heard`, and nothing is missing
  // until it falls silent). A status older than `stale_after_s` is stale
  // (the services publish every second), and older than `missing_after_s`
  // missing.
  explicit RigStatusBoard(std::optional<RigFile> rig, double stale_after_s = 3.0,
                          double missing_after_s = std::numeric_limits<double>::infinity(),
                          bool expect_heard = false);

  void Observe(const service_status_t& status, int64_t receive_utime);
  void Observe(const shape_t& shape);

  std::vector<RigStatusRow> Rows(int64_t now_utime) const;
  // Every expected program is up.
  bool Complete(int64_t now_utime) const;
  // The last shape's stages: name and duration, ms.
  const std::vector<std::pair<std::string, double>>& StageLatencies() const { return stages_; }

  std::string Table(int64_t now_utime) const;
  std::string Json(int64_t now_utime) const;

 private:
  struct Heard {
    service_status_t status;
    int64_t receive_utime = 0;
  };
  std::optional<RigFile> rig_;
  double stale_after_s_;
  double missing_after_s_;
  bool expect_heard_;
  std::map<std::pair<std::string, std::string>, Heard> heard_;  // (host, service)
  std::vector<std::pair<std::string, double>> stages_;
};

}  // namespace shapesense
