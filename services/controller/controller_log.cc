#include "services/controller/controller_log.h"

#include <charconv>
#include <cmath>
#include <cstdio>

#include "libs/control/safety_gate.h"
#include "libs/core/error.h"
#include "runtime/lcm/tendon_message.h"
#include "shapesense/tendon_command_t.hpp"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

constexpr const char* kQNames[] = {"kappa_x", "kappa_z", "eps0", "eps1"};

void CreateParent(const fs::path& path) {
  std::error_code ignored;
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ignored);
}

// The shortest text that reads back to the same double ("nan", "inf" as such).
void AppendNumber(std::string& out, double value) {
  if (std::isnan(value)) {
    out += "nan";
    return;
  }
  if (std::isinf(value)) {
    out += value > 0 ? "inf" : "-inf";
    return;
  }
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text), value);
  out.append(text, result.ptr);
}

void AppendVector(std::string& out, const Eigen::VectorXd& values, int count) {
  for (int i = 0; i < count; ++i) {
    out += ',';
    AppendNumber(out, i < values.size() ? values(i) : std::nan(""));
  }
}

// Free text in one CSV field: no commas, quotes or line breaks.
std::string CsvText(std::string text) {
  for (char& c : text) {
    if (c == ',') c = ';';
    if (c == '"') c = '\'';
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

}  // namespace

std::vector<std::string> ControllerLogColumns(int tendons) {
  std::vector<std::string> columns = {"time_s", "utime", "mode", "sent"};
  for (const char* prefix : {"target_", "sensed_"}) {
    for (const char* q : kQNames) columns.push_back(prefix + std::string(q));
  }
  columns.push_back("sensed_trigger_seq");
  columns.push_back("sensing_age_s");
  for (const char* prefix : {"proposal_", "command_", "tension_", "measured_"}) {
    for (int i = 0; i < tendons; ++i) columns.push_back(prefix + std::to_string(i));
  }
  columns.push_back("gate_reasons");
  columns.push_back("note");
  return columns;
}

ControllerLog::ControllerLog(const fs::path& csv, const fs::path& lcm, int tendons)
    : tendons_(tendons), csv_path_(csv), lcm_path_(lcm) {
  if (!csv.empty()) {
    CreateParent(csv);
    csv_.open(csv, std::ios::trunc);
    if (!csv_) throw InputError(csv.string() + ": cannot be opened for writing");
    std::string header;
    for (const std::string& column : ControllerLogColumns(tendons)) {
      header += (header.empty() ? "" : ",") + column;
    }
    csv_ << header << '\n';
  }
  if (!lcm.empty()) {
    CreateParent(lcm);
    lcm_ = std::make_unique<lcm::LogFile>(lcm.string(), "w");
    if (!lcm_->good()) throw InputError(lcm.string() + ": cannot be opened for writing");
  }
}

ControllerLog::~ControllerLog() { Flush(); }

void ControllerLog::WriteStep(const StepRecord& step) {
  if (!csv_.is_open()) return;
  std::string row;
  AppendNumber(row, step.time);
  row += ',' + std::to_string(step.utime) + ',' + CommandModeName(step.mode) + ',' +
         (step.sent ? "1" : "0");
  const Configuration none = Configuration::Constant(std::nan(""));
  AppendVector(row, step.has_target ? step.target : none, 4);
  AppendVector(row, step.sensed.valid ? step.sensed.configuration : none, 4);
  row += ',' + std::to_string(step.sensed_trigger_seq) + ',';
  AppendNumber(row, step.sensing_age);
  for (const Eigen::VectorXd* values :
       {&step.proposal, &step.command, &step.tensions, &step.measured}) {
    AppendVector(row, *values, tendons_);
  }
  row += ',' + CsvText(DescribeGateReasons(step.reasons)) + ',' + CsvText(step.note) + '\n';
  csv_ << row;
  ++rows_;
}

void ControllerLog::WriteRawEvent(const std::string& channel, std::vector<uint8_t>& bytes,
                                  int64_t utime) {
  lcm::LogEvent event{};
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(bytes.size());
  event.data = bytes.data();
  if (lcm_->writeEvent(&event) != 0) {
    write_error_ = lcm_path_.string() + ": writing failed";
  } else {
    ++events_;
  }
}

std::string ControllerLog::Flush() {
  std::string error = write_error_;
  if (csv_.is_open()) {
    csv_.flush();
    if (!csv_) error = csv_path_.string() + ": writing failed";
  }
  if (lcm_ && std::fflush(lcm_->getFilePtr()) != 0) error = lcm_path_.string() + ": writing failed";
  return error;
}

}  // namespace shapesense
