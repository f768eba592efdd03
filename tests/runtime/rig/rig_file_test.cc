// The rig file: the example parses and checks clean, each kind of mistake is
// named (unknown program, an image channel crossing hosts, a channel nobody
// publishes or reads, networks that would mix, two rigs on one group), and
// every unit written for every host passes `systemd-analyze verify`.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/rig/rig_check.h"
#include "runtime/rig/rig_units.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

const fs::path kExample = fs::path(SHAPESENSE_SOURCE_DIR) / "config" / "rig.yaml";

RigFile Example() { return ParseRigFile(ReadTextFile(kExample), kExample); }

bool Mentions(const std::vector<std::string>& problems, const std::string& text) {
  for (const std::string& problem : problems) {
    if (problem.find(text) != std::string::npos) return true;
  }
  return false;
}

std::string Joined(const std::vector<std::string>& problems) {
  std::string text;
  for (const std::string& problem : problems) text += problem + "\n";
  return text;
}

TEST(RigFileTest, TheExampleChecksClean) {
  const RigFile rig = Example();
  EXPECT_EQ(rig.name, "bench");
  ASSERT_EQ(rig.hosts.size(), 3u);
  EXPECT_EQ(rig.hosts[0].programs.size(), 3u);
  EXPECT_EQ(rig.hosts[0].programs[0].realtime_priority, 20);
  const std::vector<std::string> problems = CheckRig(rig);
  EXPECT_TRUE(problems.empty()) << Joined(problems);
}

TEST(RigFileTest, MalformedFilesNameTheKey) {
  EXPECT_THROW(ParseRigFile("rig: [", "bad.yaml"), InputError);
  try {
    ParseRigFile("rig: {name: x, cameras: 3}\nhosts: {}\n", "bad.yaml");
    FAIL() << "cameras: 3 accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("bad.yaml: rig.cameras"), std::string::npos)
        << error.what();
  }
  EXPECT_THROW(ParseRigFile("rig: {name: x}\nhosts: {a: {programs: [{config: c}]}}\n", "b.yaml"),
               InputError);
}

TEST(RigFileTest, EveryKindOfMistakeIsNamed) {
  RigFile rig = Example();
  // The carving service moved to the operator's machine: the images would cross.
  RigProgram carving = rig.hosts[0].programs[1];
  rig.hosts[0].programs.erase(rig.hosts[0].programs.begin() + 1);
  rig.hosts[2].programs.push_back(carving);
  rig.hosts[1].programs.push_back({"telepathy", "", {}, {}, 0});
  rig.rig_network = "udpm://239.255.77.1:7701?ttl=0";
  const std::vector<std::string> problems = CheckRig(rig);
  EXPECT_TRUE(Mentions(problems,
                       "SHAPESENSE_IMAGE_cam0: would cross hosts (capture on camera to "
                       "carving on operator)"))
      << Joined(problems);
  EXPECT_TRUE(Mentions(problems, "telepathy: unknown program")) << Joined(problems);
  EXPECT_TRUE(Mentions(problems, "rig.rig_network")) << Joined(problems);

  RigFile headless = Example();
  headless.hosts[0].programs.erase(headless.hosts[0].programs.begin() + 2);  // no shape service
  const std::vector<std::string> unread = CheckRig(headless);
  EXPECT_TRUE(Mentions(unread,
                       "SHAPESENSE_SHAPE: nobody publishes it (read by controller on "
                       "control, monitor on operator, lcm-logger on operator)"))
      << Joined(unread);
  headless.hosts[2].programs.clear();  // and no logger: the voxels go unread
  EXPECT_TRUE(Mentions(CheckRig(headless),
                       "SHAPESENSE_VOXELS: nobody reads it (published by carving on camera)"));

  RigFile images_out = Example();
  images_out.channels = {{"SHAPESENSE_IMAGE_cam1", Network::kRig}};
  EXPECT_TRUE(Mentions(CheckRig(images_out),
                       "SHAPESENSE_IMAGE_cam1: an image channel routed to "
                       "the rig network"));

  RigFile mixed = Example();
  mixed.rig_network = "udpm://239.255.76.67:7669?ttl=1";  // cam1's image port
  EXPECT_TRUE(Mentions(CheckRig(mixed), "among the local network's ports"));
}

TEST(RigFileTest, EveryHostHoldsTheKeyUnlessTheRigRunsInsecure) {
  RigFile rig = Example();
  EXPECT_EQ(rig.hosts[1].keys, std::vector<std::string>{"/etc/shapesense/rig.key"});
  rig.hosts[1].keys.clear();
  rig.hosts[2].keys = {"rig.key"};
  rig.hosts[0].keys = {"/etc/a.key", "/etc/b.key", "/etc/c.key"};
  const std::vector<std::string> problems = CheckRig(rig);
  EXPECT_TRUE(Mentions(problems, "hosts.control.keys: missing")) << Joined(problems);
  EXPECT_TRUE(Mentions(problems, "hosts.operator.keys: 'rig.key' is not an absolute path"))
      << Joined(problems);
  EXPECT_TRUE(Mentions(problems, "hosts.camera.keys: at most two")) << Joined(problems);
  rig = Example();
  for (RigHost& host : rig.hosts) host.keys.clear();
  rig.insecure = true;
  EXPECT_TRUE(CheckRig(rig).empty()) << Joined(CheckRig(rig));
}

TEST(RigFileTest, AHostsProgramsGetItsKeysOrTheInsecureFlag) {
  RigFile rig = Example();
  rig.hosts[0].keys = {"/etc/shapesense/old.key", "/etc/shapesense/new.key"};
  const auto environment = RigEnvironment(rig, rig.hosts[0]);
  const auto keys = std::find_if(environment.begin(), environment.end(),
                                 [](const auto& v) { return v.first == "SHAPESENSE_KEY_FILES"; });
  ASSERT_NE(keys, environment.end());
  EXPECT_EQ(keys->second, "/etc/shapesense/old.key:/etc/shapesense/new.key");
  rig.hosts[0].keys.clear();
  rig.insecure = true;
  const auto insecure = RigEnvironment(rig, rig.hosts[0]);
  EXPECT_NE(std::find(insecure.begin(), insecure.end(),
                      std::pair<std::string, std::string>{"SHAPESENSE_INSECURE", "1"}),
            insecure.end());
}

TEST(RigFileTest, TwoRigsOnOneGroupAreNamedAndApartTheyAreFine) {
  RigFile first = Example();
  RigFile second = Example();
  second.name = "bench2";
  second.prefix = "B2_";
  EXPECT_EQ(CheckRigsApart({first, second}).size(), 2u);
  second.rig_network = "udpm://239.255.77.2:7721?ttl=1";
  second.local_network = "udpm://239.255.76.68:7731?ttl=0";
  EXPECT_TRUE(CheckRigsApart({first, second}).empty());
}

std::string RunCommand(const std::string& command, int* status) {
  std::string output;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  std::array<char, 512> buffer{};
  while (pipe != nullptr && fgets(buffer.data(), buffer.size(), pipe) != nullptr) {
    output += buffer.data();
  }
  *status = pipe != nullptr ? pclose(pipe) : -1;
  return output;
}

TEST(RigFileTest, EveryHostsUnitsPassSystemdAnalyzeVerify) {
  ASSERT_TRUE(fs::exists("/usr/bin/systemd-analyze"))
      << "install the Debian package 'systemd' (deploy/install-deps.sh)";
  const RigFile rig = Example();
  const fs::path folder = fs::temp_directory_path() / ("rig_units_" + std::to_string(getpid()));
  fs::create_directories(folder);
  int units = 0;
  for (const RigHost& host : rig.hosts) {
    for (const UnitFile& unit : UnitsForHost(rig, host.name, SHAPESENSE_BIN_DIR)) {
      std::ofstream(folder / unit.file_name) << unit.text;
      EXPECT_NE(unit.text.find("Environment=\"LCM_DEFAULT_URL=" + rig.rig_network),
                std::string::npos);
      EXPECT_NE(unit.text.find("Environment=\"SHAPESENSE_CLOCK_WARNING_MS=1\""), std::string::npos);
      int status = 0;
      const std::string said = RunCommand(
          "/usr/bin/systemd-analyze verify '" + (folder / unit.file_name).string() + "'", &status);
      EXPECT_EQ(status, 0) << unit.file_name << ":\n" << said;
      const std::string name = unit.file_name.substr(0, unit.file_name.size() - 8);
      EXPECT_EQ(said.find(name), std::string::npos) << said;
      ++units;
    }
  }
  EXPECT_EQ(units, 6);
  const std::vector<UnitFile> camera = UnitsForHost(rig, "camera", SHAPESENSE_BIN_DIR);
  EXPECT_NE(camera[0].text.find("CPUSchedulingPriority=20"), std::string::npos);
  const std::vector<UnitFile> operator_units = UnitsForHost(rig, "operator", SHAPESENSE_BIN_DIR);
  EXPECT_NE(operator_units[0].text.find("Type=simple"), std::string::npos) << "lcm-logger";
  // The web monitor: the rig file's programs expected, the shape service's config.
  ASSERT_EQ(operator_units.size(), 2u);
  const std::string& monitor = operator_units[1].text;
  EXPECT_NE(monitor.find("Type=notify"), std::string::npos) << monitor;
  EXPECT_NE(monitor.find("\"--rig\" \"" + fs::absolute(rig.path).string() + "\""),
            std::string::npos)
      << monitor;
  EXPECT_NE(monitor.find("\"--shape-config\""), std::string::npos) << monitor;
  EXPECT_NE(monitor.find("\"--http\" \"127.0.0.1:8080\""), std::string::npos) << monitor;
  EXPECT_THROW(UnitsForHost(rig, "nowhere", SHAPESENSE_BIN_DIR), std::invalid_argument);
  fs::remove_all(folder);
}

}  // namespace
}  // namespace shapesense
