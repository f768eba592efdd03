// The live demo for real, for a few seconds, inside this test's private
// network namespace (tests/support): the rig-sim's fake GigE cameras (and,
// as where no namespace can be made, the capture service's simulated ones),
// the capture, carving and shape services and lcm-logger as separate
// programs. The report says frame-sets were measured within 1 mm of the
// truth and no program failed, and the log replays to the live shapes. A
// program that fails, or is missing, is named and everything else stops.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "clients/tools/demo/live_demo.h"
#include "runtime/provenance.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

#if defined(__SANITIZE_ADDRESS__)
constexpr double kRateHz = 5.0;  // everything runs about three times slower
#else
constexpr double kRateHz = 10.0;
#endif

class LiveDemoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(nettest::PrivateNetworkError(), "");
    out_ = fs::path(::testing::TempDir()) / ("live_demo_test_" + std::to_string(getpid()));
    fs::remove_all(out_);
  }
  void TearDown() override { fs::remove_all(out_); }

  LiveDemoArgs Args(DemoCameras cameras, double seconds) const {
    LiveDemoArgs args;
    args.out = out_ / "out";
    args.duration_s = seconds;
    args.rate_hz = kRateHz;
    args.cameras = cameras;
    args.network = "the test's private network namespace";
    args.bin_dir = DEMO_BIN_DIR;
    args.progress = DemoProgress::kOff;
    return args;
  }

  nlohmann::json ReadReport() const {
    std::ifstream file(out_ / "out" / "report.json");
    return nlohmann::json::parse(file);
  }

  // What every good run shows: measured, accurate, replayed to the same shapes.
  void ExpectAGoodRun(const std::string& log) const {
    const nlohmann::json report = ReadReport();
    EXPECT_EQ(report["failed"], "");
    for (const nlohmann::json& program : report["programs"]) {
      EXPECT_TRUE(program["clean"].get<bool>()) << program.dump();
      // How it ran: its program path first.
      ASSERT_FALSE(program["argv"].empty()) << program.dump();
      EXPECT_TRUE(fs::exists(program["argv"][0].get<std::string>())) << program.dump();
    }
    EXPECT_EQ(report["provenance"]["version"], ProjectVersion());
    EXPECT_FALSE(report["provenance"]["written"].get<std::string>().empty());
    EXPECT_GT(report["frame_sets"]["measured"].get<int>(), 0) << log;
    EXPECT_GT(report["accuracy_mm"]["frame_sets"].get<int>(), 0) << log;
    EXPECT_LT(report["accuracy_mm"]["centerline_rms"]["mean"].get<double>(), 1.0) << log;
    EXPECT_LT(report["accuracy_mm"]["tip"]["mean"].get<double>(), 1.0) << log;
    EXPECT_GT(report["latency_ms"]["trigger_to_shape"]["count"].get<int>(), 0);
    const fs::path lcm_log = report["log"]["path"].get<std::string>();
    EXPECT_TRUE(fs::exists(lcm_log));
    EXPECT_EQ(report["log"]["bytes"].get<int64_t>(), static_cast<int64_t>(fs::file_size(lcm_log)));
    const nlohmann::json& replay = report["replay"];
    EXPECT_EQ(replay["error"], "") << log;
    EXPECT_GT(replay["compared"].get<int>(), 0) << log;
    EXPECT_EQ(replay["identical"], replay["compared"]) << log;
  }

  fs::path out_;
  std::atomic<bool> stop_{false};
};

TEST_F(LiveDemoTest, GigECamerasMeasureWithin1mmAndTheLogReplaysToTheSameShapes) {
  std::ostringstream log;
  const LiveDemoReport report = RunLiveDemo(Args(DemoCameras::kGigE, 5.0), stop_, log);
  EXPECT_FALSE(report.interrupted);
  EXPECT_EQ(report.cameras, "gige");
  ExpectAGoodRun(log.str());
  EXPECT_TRUE(report.score.live.last_status.contains("rig_sim")) << log.str();
}

TEST_F(LiveDemoTest, SimulatedCamerasNeedNoGigE) {
  std::ostringstream log;
  const LiveDemoReport report = RunLiveDemo(Args(DemoCameras::kSimulated, 3.0), stop_, log);
  EXPECT_EQ(report.cameras, "simulated");
  EXPECT_FALSE(report.score.live.last_status.contains("rig_sim")) << "no rig-sim runs";
  ExpectAGoodRun(log.str());
}

// A folder of the real programs, but a carving service that refuses its input.
fs::path BinWithBrokenCarving(const fs::path& dir) {
  fs::create_directories(dir);
  for (const char* name : {"shapesense-rig-sim", "shapesense-capture", "shapesense-shape"}) {
    fs::create_symlink(fs::path(DEMO_BIN_DIR) / name, dir / name);
  }
  const fs::path carving = dir / "shapesense-carving";
  std::ofstream(carving) << "#!/bin/sh\necho 'shapesense-carving: building the table'\n"
                            "echo 'shapesense-carving: error: rig.yaml: expected 3 cameras' >&2\n"
                            "exit 2\n";
  fs::permissions(carving, fs::perms::owner_all);
  return dir;
}

TEST_F(LiveDemoTest, AFailingProgramIsNamedWithItsOutputAndEverythingStops) {
  LiveDemoArgs args = Args(DemoCameras::kSimulated, 4.0);
  args.bin_dir = BinWithBrokenCarving(out_ / "bin");
  std::ostringstream log;
  try {
    RunLiveDemo(args, stop_, log);
    FAIL() << "the demo ran without its carving service";
  } catch (const ProgramFailure& e) {
    EXPECT_EQ(e.program(), "carving");
    EXPECT_NE(std::string(e.what()).find("exited with status 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("expected 3 cameras"), std::string::npos) << e.what();
  }
  const nlohmann::json report = ReadReport();
  EXPECT_NE(report["failed"].get<std::string>().find("expected 3 cameras"), std::string::npos);
  std::set<std::string> ended;
  for (const nlohmann::json& program : report["programs"]) ended.insert(program["name"]);
  EXPECT_EQ(ended,
            (std::set<std::string>{"capture-background", "lcm-logger", "lcm-logger-cam0",
                                   "lcm-logger-cam1", "lcm-logger-cam2", "carving", "shape"}))
      << "started before the failure (side by side), and all stopped";
}

TEST_F(LiveDemoTest, MissingProgramsAreNamedBeforeAnythingStarts) {
  LiveDemoArgs args = Args(DemoCameras::kGigE, 4.0);
  args.bin_dir = out_ / "empty";
  fs::create_directories(args.bin_dir);
  std::ostringstream log;
  try {
    RunLiveDemo(args, stop_, log);
    FAIL() << "the demo ran without its programs";
  } catch (const ProgramFailure& e) {
    for (const char* name :
         {"shapesense-rig-sim", "shapesense-capture", "shapesense-carving", "shapesense-shape"}) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  EXPECT_FALSE(fs::exists(out_ / "out" / "logs" / "rig-sim.log"));
}

}  // namespace
}  // namespace shapesense
