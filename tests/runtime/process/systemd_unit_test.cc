// FormatUnit (runtime/process/systemd_unit.h): the unit says what is
// promised (Type=notify, the watchdog, restarts within a start limit, the
// journal), quotes the command for systemd, refuses a bad spec naming the
// field, and every unit it writes passes `systemd-analyze verify` with no
// word about it (a machine without systemd-analyze fails this test: the
// units must be checked where they are made).
#include "runtime/process/systemd_unit.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace shapesense {
namespace {

namespace fs = std::filesystem;

UnitSpec SampleSpec() {
  UnitSpec spec;
  spec.name = "shapesense-carving-rig1";
  spec.description = "shapesense carving on rig1";
  spec.command = {"/bin/true", "--config", "/etc/shapesense/carving.yaml"};
  spec.working_directory = "/tmp";
  return spec;
}

UnitSpec RealtimeSpec() {
  UnitSpec spec = SampleSpec();
  spec.name = "shapesense-controller@rig1";
  spec.cpu_affinity = {0, 1};
  spec.realtime_priority = 50;
  spec.after_units = {"shapesense-shape-rig1.service"};
  return spec;
}

UnitSpec SpacesSpec() {
  UnitSpec spec = SampleSpec();
  spec.name = "shapesense-shape_rig1.test";
  spec.description = "shape at 100% with \"quotes\"";
  spec.command = {"/bin/true", "--rig", "/srv/my rigs/rig 1.yaml", "say \"hi\" \\ 50% $HOME ;",
                  ";"};
  spec.environment = {{"LCM_DEFAULT_URL", "udpm://239.255.76.67:7667?ttl=0"},
                      {"SHAPESENSE_NOTE", "two words, 5% \"quoted\""}};
  spec.watchdog_s = 2.5;
  spec.start_timeout_s = 30;
  return spec;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

bool HasLine(const std::string& unit, const std::string& line) {
  const std::vector<std::string> lines = Lines(unit);
  return std::find(lines.begin(), lines.end(), line) != lines.end();
}

TEST(FormatUnit, SaysWhatIsPromised) {
  const std::string unit = FormatUnit(SampleSpec());
  for (const char* line : {"[Unit]",
                           "Description=shapesense carving on rig1",
                           "After=network-online.target",
                           "Wants=network-online.target",
                           "StartLimitIntervalSec=60s",
                           "StartLimitBurst=5",
                           "[Service]",
                           "Type=notify",
                           "NotifyAccess=main",
                           R"(ExecStart="/bin/true" "--config" "/etc/shapesense/carving.yaml")",
                           "WorkingDirectory=/tmp",
                           "WatchdogSec=5s",
                           "TimeoutStartSec=120s",
                           "Restart=on-failure",
                           "RestartSec=200ms",
                           "StandardOutput=journal",
                           "StandardError=journal",
                           "SyslogIdentifier=shapesense-carving-rig1",
                           "[Install]",
                           "WantedBy=multi-user.target"}) {
    EXPECT_TRUE(HasLine(unit, line)) << "no line '" << line << "' in\n" << unit;
  }
  EXPECT_LT(unit.find("[Unit]"), unit.find("[Service]"));
  EXPECT_LT(unit.find("[Service]"), unit.find("[Install]"));
  for (const char* absent : {"CPUAffinity", "CPUScheduling", "LimitRTPRIO", "Environment"}) {
    EXPECT_EQ(unit.find(absent), std::string::npos) << absent << " in\n" << unit;
  }
}

TEST(FormatUnit, PinsAndSchedulesRealtimeWhenAsked) {
  const std::string unit = FormatUnit(RealtimeSpec());
  for (const char* line :
       {"CPUAffinity=0 1", "CPUSchedulingPolicy=fifo", "CPUSchedulingPriority=50", "LimitRTPRIO=50",
        "After=network-online.target shapesense-shape-rig1.service",
        "SyslogIdentifier=shapesense-controller@rig1"}) {
    EXPECT_TRUE(HasLine(unit, line)) << "no line '" << line << "' in\n" << unit;
  }
}

TEST(FormatUnit, QuotesEveryWordLiterally) {
  const std::string unit = FormatUnit(SpacesSpec());
  // C escapes inside double quotes; "%%" and "$$" so that systemd expands no
  // specifier or variable; a quoted ";" is an argument, not a separator.
  EXPECT_TRUE(HasLine(unit, R"(ExecStart="/bin/true" "--rig" "/srv/my rigs/rig 1.yaml" )"
                            R"("say \"hi\" \\ 50%% $$HOME ;" ";")"))
      << unit;
  EXPECT_TRUE(HasLine(unit, R"(Environment="LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=0")"))
      << unit;
  EXPECT_TRUE(HasLine(unit, R"(Environment="SHAPESENSE_NOTE=two words, 5%% \"quoted\"")")) << unit;
  EXPECT_TRUE(HasLine(unit, R"(Description=shape at 100%% with "quotes")")) << unit;
  EXPECT_TRUE(HasLine(unit, "WatchdogSec=2500ms")) << unit;
  EXPECT_TRUE(HasLine(unit, "TimeoutStartSec=30s")) << unit;
}

struct BadSpec {
  std::string field;
  std::function<void(UnitSpec&)> spoil;
};

TEST(FormatUnit, RefusesABadSpecNamingTheField) {
  const std::vector<BadSpec> bad = {
      {"name", [](UnitSpec& s) { s.name.clear(); }},
      {"name", [](UnitSpec& s) { s.name = "carving rig1"; }},
      {"name", [](UnitSpec& s) { s.name = "carving/rig1"; }},
      {"description", [](UnitSpec& s) { s.description = "two\nlines"; }},
      {"command", [](UnitSpec& s) { s.command.clear(); }},
      {"command", [](UnitSpec& s) { s.command[0] = "bin/true"; }},
      {"command", [](UnitSpec& s) { s.command.push_back("new\nline"); }},
      {"working_directory", [](UnitSpec& s) { s.working_directory = "relative"; }},
      {"environment",
       [](UnitSpec& s) {
         s.environment = {{"1BAD", "x"}};
       }},
      {"environment",
       [](UnitSpec& s) {
         s.environment = {{"A=B", "x"}};
       }},
      {"environment",
       [](UnitSpec& s) {
         s.environment = {{"GOOD", "new\nline"}};
       }},
      {"watchdog_s", [](UnitSpec& s) { s.watchdog_s = 0; }},
      {"watchdog_s", [](UnitSpec& s) { s.watchdog_s = std::nan(""); }},
      {"start_timeout_s", [](UnitSpec& s) { s.start_timeout_s = -1; }},
      {"start_limit_interval_s", [](UnitSpec& s) { s.start_limit_interval_s = 0; }},
      {"restart_sec_ms", [](UnitSpec& s) { s.restart_sec_ms = -1; }},
      {"start_limit_burst", [](UnitSpec& s) { s.start_limit_burst = 0; }},
      {"cpu_affinity",
       [](UnitSpec& s) {
         s.cpu_affinity = {0, -1};
       }},
      {"realtime_priority", [](UnitSpec& s) { s.realtime_priority = 100; }},
      {"realtime_priority", [](UnitSpec& s) { s.realtime_priority = -1; }},
      {"after_units", [](UnitSpec& s) { s.after_units = {"a b.service"}; }},
  };
  for (const BadSpec& each : bad) {
    UnitSpec spec = SampleSpec();
    each.spoil(spec);
    try {
      FormatUnit(spec);
      ADD_FAILURE() << "accepted a bad " << each.field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(each.field + ":"), std::string::npos)
          << "expected the field '" << each.field << "' named in: " << e.what();
    }
  }
}

struct CommandResult {
  int exit_code = -1;
  std::string output;
};

// Runs a shell command with stderr merged into the output.
CommandResult Run(const std::string& command) {
  CommandResult result;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) result.output += buffer.data();
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// What systemd-analyze verify says about this unit (it may also talk about
// other units of the machine: those lines are not ours).
std::string VerifyUnit(const fs::path& folder, const UnitSpec& spec, int* exit_code) {
  const fs::path file = folder / (spec.name + ".service");
  std::ofstream(file) << FormatUnit(spec);
  const CommandResult result =
      Run(std::string(SYSTEMD_ANALYZE) + " verify '" + file.string() + "'");
  *exit_code = result.exit_code;
  std::string ours;
  for (const std::string& line : Lines(result.output)) {
    if (line.find(spec.name) != std::string::npos) ours += line + '\n';
  }
  return ours;
}

TEST(FormatUnit, EveryUnitPassesSystemdAnalyzeVerify) {
  ASSERT_TRUE(fs::exists(SYSTEMD_ANALYZE))
      << SYSTEMD_ANALYZE << " is missing: install the Debian package 'systemd' "
      << "(deploy/install-deps.sh) to check the unit files";
  const fs::path folder =
      fs::temp_directory_path() / ("shapesense_units_" + std::to_string(getpid()));
  fs::create_directories(folder);
  for (const UnitSpec& spec : {SampleSpec(), RealtimeSpec(), SpacesSpec()}) {
    int exit_code = -1;
    const std::string said = VerifyUnit(folder, spec, &exit_code);
    EXPECT_EQ(said, "") << "systemd-analyze verify on " << spec.name << ":\n" << said;
    EXPECT_EQ(exit_code, 0) << spec.name;
  }
  fs::remove_all(folder);
}

}  // namespace
}  // namespace shapesense
