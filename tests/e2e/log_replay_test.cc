// A live run recorded by lcm-logger and replayed by the real `shapesense
// replay`: the replay measures the same shapes as the live services did, for
// the same frame-sets, bit for bit; and lcm-logplayer reads the log back.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nlohmann/json.hpp>

#include "runtime/lcm/channels.h"
#include "runtime/lcm/wire_check.h"
#include "tests/e2e/live_pipeline.h"
#include "tests/support/network_test.h"

namespace shapesense::e2e {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using Key = std::pair<int64_t, int64_t>;  // trigger sequence and time

Key KeyOf(const shape_t& shape) { return {shape.trigger_seq, shape.trigger_utime}; }

// The shapes of an LCM log on the shape channel.
std::map<Key, shape_t> ShapesInLog(const fs::path& path) {
  std::map<Key, shape_t> shapes;
  lcm::LogFile log(path.string(), "r");
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    shape_t shape;
    if (event->channel != channels::kShape) continue;
    if (DecodeMessage(event->data, static_cast<size_t>(event->datalen), &shape).empty()) {
      shapes[KeyOf(shape)] = shape;
    }
  }
  return shapes;
}

// Events per channel of a log.
std::map<std::string, int> ChannelCounts(const fs::path& path) {
  std::map<std::string, int> counts;
  lcm::LogFile log(path.string(), "r");
  while (const lcm::LogEvent* event = log.readNextEvent()) ++counts[event->channel];
  return counts;
}

// The logged rate is lower than the live tests': a 640x480 frame-set is
// 2.8 MB on disk, and the log only has to hold a few dozen of them.
double LogRate() { return UnderSanitizers() ? 5.0 : 15.0; }

TEST(LogReplayTest, ReplayOfTheRecordedRunGivesTheLiveShapesExactly) {
  ASSERT_EQ(nettest::PrivateNetworkError(), "");
  PipelineOptions options;
  options.rate_hz = LogRate();
  LivePipeline pipeline("replay", options);
  ASSERT_EQ(pipeline.StartServices(), "");
  const fs::path log = pipeline.dir() / "run.lcmlog";
  ASSERT_EQ(pipeline.StartLogger(log), "");
  ASSERT_EQ(pipeline.RunCapture(4.0), "");
  pipeline.Drain();
  ASSERT_EQ(pipeline.StopAll(), "") << "a process did not stop cleanly";
  std::map<Key, shape_t> live;
  for (const auto& shape : pipeline.recorder().Shapes()) live[KeyOf(shape.message)] = shape.message;
  ASSERT_GE(live.size(), 0.5 * options.rate_hz * 3.0) << "too few live shapes";

  // The loggers recorded every channel, the live shapes among them; each
  // camera's images in the log of its port, and only there.
  const std::map<std::string, int> counts = ChannelCounts(log);
  for (const std::string& channel :
       {std::string(channels::kVoxels), std::string(channels::kSilhouettes),
        std::string(channels::kShape), std::string(channels::kTruth), channels::Status("capture"),
        channels::Status("carving"), channels::Status("shape"), channels::Status("rig_sim")}) {
    EXPECT_GT(counts.count(channel) ? counts.at(channel) : 0, 0) << channel << " not in the log";
  }
  EXPECT_EQ(ShapesInLog(log).size(), live.size());
  const std::vector<fs::path> image_logs = pipeline.ImageLogs(log);
  for (size_t k = 0; k < image_logs.size(); ++k) {
    const std::string camera = pipeline.rig().cameras[k].name;
    EXPECT_EQ(counts.count(channels::Image(camera)), 0u) << "images on the rig's port";
    const std::map<std::string, int> images = ChannelCounts(image_logs[k]);
    EXPECT_EQ(images.size(), 1u) << image_logs[k] << " holds other channels than its camera's";
    EXPECT_GT(images.count(channels::Image(camera)) ? images.at(channels::Image(camera)) : 0, 0)
        << camera << "'s images not in " << image_logs[k];
  }

  const fs::path jsonl = pipeline.dir() / "replay" / "shapes.jsonl";
  const fs::path shapes_log = pipeline.dir() / "replay" / "shapes.lcmlog";
  std::vector<std::string> replay_argv = {E2E_SHAPESENSE, "replay"};
  for (const fs::path& image_log : image_logs) replay_argv.push_back(image_log.string());
  for (const std::string& arg :
       {std::string("--out"), jsonl.string(), std::string("--out-log"), shapes_log.string(),
        std::string("--config"), pipeline.CarvingConfig().string(), std::string("--shape-config"),
        pipeline.ShapeConfig().string()}) {
    replay_argv.push_back(arg);
  }
  ChildProcess replay(replay_argv);
  // It writes to standard error; its standard output closes when it ends.
  replay.WaitForLine("(nothing)", milliseconds(120000));
  ASSERT_EQ(replay.Stop(), 0) << "shapesense replay failed or did not end within two minutes";

  const std::map<Key, shape_t> replayed = ShapesInLog(shapes_log);
  uintmax_t image_bytes = 0;
  for (const fs::path& image_log : image_logs) image_bytes += fs::file_size(image_log);
  std::cout << live.size() << " shapes measured live, " << replayed.size() << " replayed from "
            << image_bytes / 1000000 << " MB of image logs\n";
  EXPECT_EQ(replayed.size(), live.size());
  int identical = 0;
  for (const auto& [key, shape] : live) {
    const auto it = replayed.find(key);
    if (it == replayed.end()) {
      ADD_FAILURE() << "frame-set " << key.first << " measured live, not in the replay";
      continue;
    }
    EXPECT_EQ(it->second.valid, shape.valid);
    EXPECT_EQ(it->second.centerline, shape.centerline) << "frame-set " << key.first;
    EXPECT_EQ(it->second.curvature, shape.curvature) << "frame-set " << key.first;
    EXPECT_EQ(it->second.markers, shape.markers) << "frame-set " << key.first;
    EXPECT_EQ(it->second.centerline_residual_mm, shape.centerline_residual_mm);
    identical += it->second.centerline == shape.centerline ? 1 : 0;
  }
  std::cout << identical << " of " << live.size() << " centrelines identical to the live ones\n";

  // The JSON lines carry the same centrelines, rounded to 0.1 µm.
  std::ifstream lines(jsonl);
  std::string line;
  int json_shapes = 0;
  while (std::getline(lines, line)) {
    const nlohmann::json parsed = nlohmann::json::parse(line);
    const Key key{parsed.at("trigger_seq").get<int64_t>(),
                  parsed.at("trigger_utime").get<int64_t>()};
    ASSERT_TRUE(live.contains(key)) << line.substr(0, 80);
    const auto& centerline = live.at(key).centerline;
    ASSERT_EQ(parsed.at("centerline").size(), centerline.size());
    for (size_t k = 0; k < centerline.size(); ++k) {
      for (size_t c = 0; c < 3; ++c) {
        EXPECT_NEAR(parsed["centerline"][k][c].get<double>(), centerline[k][c], 0.6e-4);
      }
    }
    ++json_shapes;
  }
  EXPECT_EQ(json_shapes, static_cast<int>(live.size()));

  // lcm-logplayer plays the log's small channels back to a listener.
  Recorder listener;
  ChildProcess player({"/usr/bin/lcm-logplayer", "--lcm-url=" + std::string(kLcmUrl), "--speed=4",
                       "--regexp=SHAPESENSE_(SHAPE|TRUTH)", log.string()});
  const auto played_all = [&] {
    return listener.ShapeCount() >= static_cast<size_t>(counts.at(channels::kShape)) &&
           listener.Truths().size() >= static_cast<size_t>(counts.at(channels::kTruth));
  };
  EXPECT_TRUE(listener.WaitFor(played_all, milliseconds(30000)))
      << "lcm-logplayer played " << listener.ShapeCount() << " of " << counts.at(channels::kShape)
      << " shapes";
  player.Stop();
}

}  // namespace
}  // namespace shapesense::e2e
