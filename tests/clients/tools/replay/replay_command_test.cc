// `shapesense replay`: the shapes measured live over memq:// (carving and
// shape services) and those of a replay of the recorded images are the
// same, bit for bit; bad input is refused before any work; malformed log
// events are counted.
#include "clients/tools/replay/replay_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/service_config.h"
#include "tests/support/service_test_options.h"
#include "tests/support/test_rig.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using testing::Encode;
using testing::HandleUntil;
using testing::TestRig;

void WriteEvent(lcm::LogFile& log, const std::string& channel, std::vector<uint8_t> bytes,
                int64_t timestamp) {
  lcm::LogEvent event{};
  event.timestamp = timestamp;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(bytes.size());
  event.data = bytes.data();
  ASSERT_EQ(log.writeEvent(&event), 0);
}

class ReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("replay_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    rig_.WriteFiles(dir_ / "rig");
    CarvingServiceOptions carving = testing::TestCarvingOptions();
    carving.rig = "rig/rig.yaml";  // relative to the config's folder
    carving.backgrounds = "rig/background";
    WriteFileAtomically(dir_ / "carving.yaml", OptionsToDocumentedYaml(carving));
    ShapeServiceOptions shape = testing::TestShapeOptions();
    shape.rig = carving.rig;
    WriteFileAtomically(dir_ / "shape.yaml", OptionsToDocumentedYaml(shape));
  }
  void TearDown() override { fs::remove_all(dir_); }

  ReplayArgs Args() const {
    ReplayArgs args;
    args.logs = {dir_ / "images.lcmlog"};
    args.config = dir_ / "carving.yaml";
    args.shape_config = dir_ / "shape.yaml";
    args.progress = false;
    return args;
  }

  // The live pipeline over memq:// on `sets` rendered frame-sets, its images
  // recorded as lcm-logger would; returns the shapes by trigger sequence.
  std::map<int64_t, shape_t> RunLive(int sets) {
    ServiceArgs carving_args;
    carving_args.config = dir_ / "carving.yaml";
    ServiceArgs shape_args;
    shape_args.config = dir_ / "shape.yaml";
    const CarvingServiceOptions carving = LoadCarvingServiceOptions(carving_args);
    const ShapeServiceOptions shape = LoadShapeServiceOptions(shape_args);
    LcmBus bus("memq://");
    CarvingService carving_service(carving, LoadRigSetup(carving.rig, carving.backgrounds), bus);
    ShapeService shape_service(shape, LoadRigSetup(shape.rig, {}).rig, bus);
    lcm::LogFile recording((dir_ / "images.lcmlog").string(), "w");
    // A malformed event on a camera channel, as a faulty sender would leave in a log.
    WriteEvent(recording, channels::Image("cam0"), std::vector<uint8_t>(40, 0x33), NowUtime());
    bus.Subscribe<image_t>(
        channels::kImagePattern,
        [&](const image_t& image, const std::string& channel, int64_t receive_utime) {
          WriteEvent(recording, channel, Encode(image), receive_utime);
        });
    std::map<int64_t, shape_t> shapes;
    bus.Subscribe<shape_t>(channels::kShape, [&](const shape_t& s, const std::string&, int64_t) {
      shapes[s.trigger_seq] = s;
    });
    for (int i = 0; i < sets; ++i) {
      std::vector<image_t> images = rig_.Messages(i, 10 + i, 0);
      testing::Stamp(&images, NowUtime());
      for (const image_t& image : images) bus.Publish(channels::Image(image.camera), image);
    }
    EXPECT_TRUE(HandleUntil(
        bus, [&] { return shapes.size() == static_cast<size_t>(sets); },
        [&](int64_t now) {
          carving_service.Poll(now);
          shape_service.Poll(now);
        }));
    return shapes;
  }

  TestRig rig_{6};
  fs::path dir_;
};

TEST_F(ReplayTest, ReplayingTheRecordedImagesGivesTheLiveShapesExactly) {
  constexpr int kSets = 4;
  const std::map<int64_t, shape_t> live = RunLive(kSets);
  ASSERT_EQ(live.size(), static_cast<size_t>(kSets));

  ReplayArgs args = Args();
  args.out = dir_ / "out" / "shapes.jsonl";
  args.out_log = dir_ / "out" / "shapes.lcmlog";
  std::vector<shape_t> replayed;
  std::ostringstream log;
  const ReplaySummary summary =
      RunReplay(args, log, [&](const shape_t& s) { replayed.push_back(s); });
  EXPECT_EQ(summary.images, 3 * kSets + 1);
  EXPECT_EQ(summary.rejected, 1);
  EXPECT_EQ(summary.frame_sets, kSets);
  EXPECT_EQ(summary.measured, kSets);
  EXPECT_EQ(summary.dropped_sets, 0);

  ASSERT_EQ(replayed.size(), static_cast<size_t>(kSets));
  for (const shape_t& shape : replayed) {
    ASSERT_EQ(live.count(shape.trigger_seq), 1u) << shape.trigger_seq;
    const shape_t& truth = live.at(shape.trigger_seq);
    ASSERT_TRUE(truth.valid);
    EXPECT_EQ(shape.valid, truth.valid);
    EXPECT_EQ(shape.trigger_utime, truth.trigger_utime);
    EXPECT_EQ(shape.centerline, truth.centerline) << "frame-set " << shape.trigger_seq;
    EXPECT_EQ(shape.curvature, truth.curvature);
    EXPECT_EQ(shape.markers, truth.markers);
    EXPECT_EQ(shape.length, truth.length);
    EXPECT_EQ(shape.centerline_residual_mm, truth.centerline_residual_mm);
    EXPECT_EQ(shape.num_stage_times, 5);
  }

  // The LCM log holds the same shapes; the JSON lines, the offline command's format.
  lcm::LogFile shapes_log(args.out_log.string(), "r");
  int events = 0;
  while (const lcm::LogEvent* event = shapes_log.readNextEvent()) {
    EXPECT_EQ(event->channel, channels::kShape);
    shape_t shape;
    ASSERT_EQ(DecodeMessage(event->data, static_cast<size_t>(event->datalen), &shape), "");
    EXPECT_EQ(shape.centerline, live.at(shape.trigger_seq).centerline);
    ++events;
  }
  EXPECT_EQ(events, kSets);
  std::ifstream json(args.out);
  std::string line;
  int lines = 0;
  while (std::getline(json, line)) {
    const nlohmann::json parsed = nlohmann::json::parse(line);
    const int64_t seq = parsed.at("trigger_seq").get<int64_t>();
    EXPECT_EQ(parsed.at("frame"), "0000" + std::to_string(seq));
    EXPECT_TRUE(parsed.at("valid").get<bool>());
    const auto& centerline = live.at(seq).centerline;
    ASSERT_EQ(parsed.at("centerline").size(), centerline.size());
    for (size_t k = 0; k < centerline.size(); ++k) {
      for (size_t c = 0; c < 3; ++c)
        EXPECT_NEAR(parsed["centerline"][k][c].get<double>(), centerline[k][c], 1e-4);
    }
    EXPECT_TRUE(parsed.at("stage_ms").contains("carving"));
    ++lines;
  }
  EXPECT_EQ(lines, kSets);
}

TEST_F(ReplayTest, TheCommandLineRunsIt) {
  RunLive(1);
  CLI::App app;
  AddReplayCommand(app);
  const std::string out = (dir_ / "cli.jsonl").string();
  const std::string log = (dir_ / "images.lcmlog").string();
  const std::string config = (dir_ / "carving.yaml").string();
  const std::string shape = (dir_ / "shape.yaml").string();
  std::vector<const char*> argv = {"shapesense",   "replay",         log.c_str(),
                                   "--out",        out.c_str(),      "--config",
                                   config.c_str(), "--shape-config", shape.c_str()};
  app.parse(static_cast<int>(argv.size()), const_cast<char**>(argv.data()));
  EXPECT_NE(ReadTextFile(out).find("\"frame\":\"000010\""), std::string::npos);
}

TEST_F(ReplayTest, BadInputIsRefusedBeforeAnyWork) {
  std::ostringstream log;
  ReplayArgs args = Args();
  args.out = dir_ / "shapes.jsonl";
  EXPECT_THROW(RunReplay(args, log), InputError);  // no log yet
  { lcm::LogFile empty(args.logs[0].string(), "w"); }
  ReplayArgs no_output = Args();
  EXPECT_THROW(RunReplay(no_output, log), InputError);
  ReplayArgs no_rig = args;
  no_rig.config.clear();
  EXPECT_THROW(RunReplay(no_rig, log), InputError);
  // With the rig and backgrounds on the command line, no config is needed.
  no_rig.shape_config.clear();
  no_rig.rig = dir_ / "rig" / "rig.yaml";
  no_rig.backgrounds = dir_ / "rig" / "background";
  const ReplaySummary summary = RunReplay(no_rig, log);
  EXPECT_EQ(summary.events, 0);
  EXPECT_TRUE(fs::exists(args.out));
  ReplayArgs no_logs = args;
  no_logs.logs.clear();
  EXPECT_THROW(RunReplay(no_logs, log), InputError);
}

// A rig's recording is one log per camera's port (runtime/lcm/image_buses.h):
// replay merges them by time and measures what one log gives.
TEST_F(ReplayTest, ImagesSplitOverSeveralLogsGiveTheSameShapes) {
  constexpr int kSets = 2;
  const std::map<int64_t, shape_t> live = RunLive(kSets);
  std::map<std::string, std::unique_ptr<lcm::LogFile>> split;
  {
    lcm::LogFile all((dir_ / "images.lcmlog").string(), "r");
    while (const lcm::LogEvent* event = all.readNextEvent()) {
      std::unique_ptr<lcm::LogFile>& file = split[event->channel];
      if (!file) {
        file = std::make_unique<lcm::LogFile>(
            (dir_ / ("split" + std::to_string(split.size()) + ".lcmlog")).string(), "w");
      }
      lcm::LogEvent copy = *event;
      ASSERT_EQ(file->writeEvent(&copy), 0);
    }
  }
  ASSERT_EQ(split.size(), 3u);  // one per camera
  split.clear();                // closes them
  ReplayArgs args = Args();
  args.out = dir_ / "split.jsonl";
  args.logs = {dir_ / "split3.lcmlog", dir_ / "split1.lcmlog", dir_ / "split2.lcmlog"};
  std::map<int64_t, shape_t> replayed;
  std::ostringstream log;
  RunReplay(args, log, [&](const shape_t& s) { replayed[s.trigger_seq] = s; });
  ASSERT_EQ(replayed.size(), live.size());
  for (const auto& [seq, shape] : live) {
    EXPECT_EQ(replayed.at(seq).centerline, shape.centerline) << "frame-set " << seq;
  }
}

}  // namespace
}  // namespace shapesense
