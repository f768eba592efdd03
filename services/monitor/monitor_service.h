#pragma once

// shapesense-monitor: the rig's live web view. Subscribes to what people
// want to see (shapes, camera previews and silhouettes, targets, the
// controller's commands and actuators, every program's status) and serves
// it to browsers over HTTP and a WebSocket (web_server.h), as the page in
// services/monitor/web draws it (docs/monitor.md).
//
// Read-only: it publishes its own status and nothing else, except an
// engaged e-stop when an operator presses the page's button, which appears
// only when a token is configured and is checked against it. An engaged
// e-stop is acted on unsigned (docs/security.md), so the monitor needs no
// rig key to stop the robot, and can never release it.
#include <atomic>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>

#include "shapesense/service_status_t.hpp"

namespace shapesense {

struct MonitorArgs {
  std::optional<std::string> lcm_url;  // the rig network; empty: LCM_DEFAULT_URL
  std::string http = "127.0.0.1:8080";
  // Calibration (the rig's cameras, OpenCV YAML): to project the shape
  // into each camera. Empty: pictures without the projected shape.
  std::filesystem::path calibration;
  // The rig file (hosts and programs): the health table's expected programs.
  std::filesystem::path rig;
  // The shape service's config: its rig and configuration section draw a
  // configuration target (and give the calibration when none is given).
  std::filesystem::path shape_config;
  // The page; empty: share/shapesense/monitor beside the executable's folder.
  std::filesystem::path assets;
  // A file holding the e-stop token (mode 0600); empty: no e-stop button.
  std::filesystem::path estop_token_file;
  double duration_s = 0.0;  // 0: until stopped
};

// The e-stop token from its file: one line of at least 16 characters, the
// file readable by its owner only. InputError naming the file otherwise.
std::string ReadEstopToken(const std::filesystem::path& file);

// Whether a browser's e-stop request carries the token (in constant time).
bool TokenMatches(const std::string& expected, const std::string& given);

// Serves until `stop` or the duration; prints the URL once it listens.
// InputError on bad arguments or files.
service_status_t RunMonitor(const MonitorArgs& args, const std::atomic<bool>& stop,
                            std::ostream& log);

}  // namespace shapesense
