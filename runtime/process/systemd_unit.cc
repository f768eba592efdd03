#include "runtime/process/systemd_unit.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace shapesense {
namespace {

[[noreturn]] void Invalid(const std::string& field, const std::string& why) {
  throw std::invalid_argument("unit spec: " + field + ": " + why);
}

bool IsUnitNameCharacter(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '@' ||
         c == '-';
}

bool HasControlCharacter(const std::string& text) {
  return std::any_of(text.begin(), text.end(),
                     [](char c) { return std::iscntrl(static_cast<unsigned char>(c)) != 0; });
}

bool IsIdentifier(const std::string& name) {
  const auto word = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
  };
  return !name.empty() && std::isdigit(static_cast<unsigned char>(name[0])) == 0 &&
         std::all_of(name.begin(), name.end(), word);
}

void ValidateUnitName(const std::string& field, const std::string& name) {
  // systemd's limit is 255 characters with the ".service" suffix.
  if (name.empty() || name.size() > 240) Invalid(field, "expected 1-240 characters");
  if (!std::all_of(name.begin(), name.end(), IsUnitNameCharacter)) {
    Invalid(field, "'" + name + "': expected letters, digits and _.@- only");
  }
}

// Every text goes onto one line of the file: a newline would end the setting.
void ValidateLine(const std::string& field, const std::string& text) {
  if (HasControlCharacter(text)) Invalid(field, "contains a control character (newline, tab...)");
}

void ValidateCommand(const std::vector<std::string>& command) {
  if (command.empty() || command[0].empty() || command[0][0] != '/') {
    Invalid("command", "expected an absolute executable path first");
  }
  for (const std::string& argument : command) ValidateLine("command", argument);
}

void ValidateEnvironment(const std::vector<std::pair<std::string, std::string>>& environment) {
  for (const auto& [name, value] : environment) {
    if (!IsIdentifier(name)) Invalid("environment", "'" + name + "': expected a C identifier");
    ValidateLine("environment", value);
  }
}

void ValidateDuration(const std::string& field, double seconds) {
  // systemd counts in microseconds; under a millisecond is surely a mistake.
  if (!(std::isfinite(seconds) && seconds >= 0.001)) {
    Invalid(field, "expected at least 0.001 s, got " + std::to_string(seconds));
  }
}

void ValidateScheduling(const UnitSpec& spec) {
  for (const int cpu : spec.cpu_affinity) {
    if (cpu < 0 || cpu > 4095)
      Invalid("cpu_affinity", "expected CPUs 0-4095, got " + std::to_string(cpu));
  }
  if (spec.realtime_priority < 0 || spec.realtime_priority > 99) {
    Invalid("realtime_priority", "expected 0-99, got " + std::to_string(spec.realtime_priority));
  }
}

void Validate(const UnitSpec& spec) {
  ValidateUnitName("name", spec.name);
  ValidateLine("description", spec.description);
  ValidateCommand(spec.command);
  if (!spec.working_directory.empty() && spec.working_directory[0] != '/') {
    Invalid("working_directory", "expected an absolute path, got '" + spec.working_directory + "'");
  }
  ValidateLine("working_directory", spec.working_directory);
  ValidateEnvironment(spec.environment);
  ValidateDuration("watchdog_s", spec.watchdog_s);
  ValidateDuration("start_timeout_s", spec.start_timeout_s);
  ValidateDuration("start_limit_interval_s", spec.start_limit_interval_s);
  if (spec.restart_sec_ms < 0) Invalid("restart_sec_ms", "expected 0 or more");
  if (spec.start_limit_burst < 1) Invalid("start_limit_burst", "expected 1 or more");
  ValidateScheduling(spec);
  for (const std::string& unit : spec.after_units) ValidateUnitName("after_units", unit);
}

// systemd expands "%x" specifiers in most settings: "%%" is a literal "%".
std::string EscapeSpecifiers(const std::string& text) {
  std::string escaped;
  for (const char c : text) escaped += c == '%' ? std::string("%%") : std::string(1, c);
  return escaped;
}

// One word of ExecStart= or Environment=: double-quoted with C escapes, "%"
// as "%%", and (ExecStart only) "$" as "$$" so that no variable is expanded.
std::string Quote(const std::string& word, bool escape_dollar) {
  std::string quoted = "\"";
  for (const char c : word) {
    if (c == '\\' || c == '"') quoted += '\\';
    if (c == '%') quoted += '%';
    if (c == '$' && escape_dollar) quoted += '$';
    quoted += c;
  }
  return quoted + '"';
}

// A time span in whole milliseconds, as seconds when it is whole seconds.
std::string Span(double seconds) {
  const auto ms = static_cast<long long>(std::llround(seconds * 1000.0));
  return ms % 1000 == 0 ? std::to_string(ms / 1000) + "s" : std::to_string(ms) + "ms";
}

template <class Item, class Format>
std::string Joined(const std::vector<Item>& items, Format format) {
  std::string line;
  for (const Item& item : items) {
    if (!line.empty()) line += ' ';
    line += format(item);
  }
  return line;
}

void WriteUnitSection(const UnitSpec& spec, std::ostream& out) {
  std::vector<std::string> after{"network-online.target"};
  after.insert(after.end(), spec.after_units.begin(), spec.after_units.end());
  out << "[Unit]\n"
      << "Description=" << EscapeSpecifiers(spec.description) << '\n'
      << "After=" << Joined(after, EscapeSpecifiers) << '\n'
      << "Wants=network-online.target\n"
      << "StartLimitIntervalSec=" << Span(spec.start_limit_interval_s) << '\n'
      << "StartLimitBurst=" << spec.start_limit_burst << "\n\n";
}

void WriteScheduling(const UnitSpec& spec, std::ostream& out) {
  if (!spec.cpu_affinity.empty()) {
    out << "CPUAffinity=" << Joined(spec.cpu_affinity, [](int cpu) { return std::to_string(cpu); })
        << '\n';
  }
  if (spec.realtime_priority > 0) {
    out << "CPUSchedulingPolicy=fifo\n"
        << "CPUSchedulingPriority=" << spec.realtime_priority << '\n'
        << "LimitRTPRIO=" << spec.realtime_priority << '\n';
  }
}

void WriteServiceSection(const UnitSpec& spec, std::ostream& out) {
  out << "[Service]\n";
  if (spec.notify) {
    // Only the program itself may say ready or ping the watchdog, not a child it starts.
    out << "Type=notify\nNotifyAccess=main\n";
  } else {
    out << "Type=simple\n";
  }
  out << "ExecStart=" << Joined(spec.command, [](const std::string& w) { return Quote(w, true); })
      << '\n';
  if (!spec.working_directory.empty()) {
    out << "WorkingDirectory=" << EscapeSpecifiers(spec.working_directory) << '\n';
  }
  for (const auto& [name, value] : spec.environment) {
    std::string assignment = name;
    assignment += '=';
    assignment += value;
    out << "Environment=" << Quote(assignment, false) << '\n';
  }
  if (spec.notify) out << "WatchdogSec=" << Span(spec.watchdog_s) << '\n';
  out << "TimeoutStartSec=" << Span(spec.start_timeout_s) << '\n'
      << "Restart=on-failure\n"
      << "RestartSec=" << spec.restart_sec_ms << "ms\n";
  WriteScheduling(spec, out);
  out << "StandardOutput=journal\n"
      << "StandardError=journal\n"
      << "SyslogIdentifier=" << spec.name << "\n\n";
}

}  // namespace

std::string FormatUnit(const UnitSpec& spec) {
  Validate(spec);
  std::ostringstream out;
  out << "# Generated by shapesense (runtime/process/systemd_unit.h).\n";
  WriteUnitSection(spec, out);
  WriteServiceSection(spec, out);
  out << "[Install]\nWantedBy=multi-user.target\n";
  return out.str();
}

}  // namespace shapesense
