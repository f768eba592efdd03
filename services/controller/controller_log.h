#pragma once

// The controller service's logs (docs/controller.md, "Logs"): a CSV with one
// row per control step, and an LCM log (lcm::LogFile) of the messages it
// published on SHAPESENSE_TENDON_COMMAND / _STATE and of the sensed shapes it
// used (on SHAPESENSE_SHAPE, the centreline left out). Both are written as
// the loop runs, flushed periodically and on every stop.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "libs/control/controllers.h"

namespace shapesense {

// One control step: what went in, what the gate made of it, what was sent.
struct StepRecord {
  int64_t utime = 0;  // the controller's clock, µs since the epoch
  double time = 0.0;  // s since the start
  bool has_target = false;
  Configuration target = Configuration::Zero();
  SensedConfiguration sensed;  // its time on the controller's clock, s since the start
  int64_t sensed_trigger_seq = -1;
  double sensing_age = 0.0;  // s (inf: nothing sensed yet)
  Eigen::VectorXd proposal;  // mm (the last command when there is no target)
  Eigen::VectorXd command;   // what the gate let through, mm
  Eigen::VectorXd tensions;  // of the command per the model, N
  Eigen::VectorXd measured;  // the actuators' positions, mm
  bool sent = false;         // the command went to the driver
  int8_t mode = 0;           // tendon_command_t::MODE_*
  uint32_t reasons = 0;      // GateReason flags
  std::string note;          // what happened at this step (a rejected target, a stop, ...)
};

class ControllerLog {
 public:
  // Opens both logs (creating their folders) and writes the CSV header; an
  // empty path leaves that log out. Throws InputError naming the path when a
  // log cannot be opened.
  ControllerLog(const std::filesystem::path& csv, const std::filesystem::path& lcm, int tendons);
  ~ControllerLog();
  ControllerLog(const ControllerLog&) = delete;
  ControllerLog& operator=(const ControllerLog&) = delete;

  void WriteStep(const StepRecord& step);
  // An LCM event: the encoded message on `channel` at `utime`.
  template <class Message>
  void WriteEvent(const std::string& channel, const Message& message, int64_t utime) {
    if (!lcm_) return;
    std::vector<uint8_t> bytes(static_cast<size_t>(message.getEncodedSize()));
    message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    WriteRawEvent(channel, bytes, utime);
  }
  // Pushes both logs to the file system. Returns "" or what failed.
  std::string Flush();

  int64_t rows() const { return rows_; }
  int64_t events() const { return events_; }

 private:
  void WriteRawEvent(const std::string& channel, std::vector<uint8_t>& bytes, int64_t utime);

  int tendons_;
  std::filesystem::path csv_path_;
  std::filesystem::path lcm_path_;
  std::ofstream csv_;
  std::unique_ptr<lcm::LogFile> lcm_;
  int64_t rows_ = 0;
  int64_t events_ = 0;
  std::string write_error_;
};

// The CSV's column names, in order (tendons columns per vector).
std::vector<std::string> ControllerLogColumns(int tendons);

}  // namespace shapesense
