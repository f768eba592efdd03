// The rig-sim's command-line options: every bad value is an InputError that
// names the option, raised before any camera is served.

#include <gtest/gtest.h>

#include <atomic>

#include "libs/core/error.h"
#include "libs/sim/scene_generators.h"
#include "services/rig_sim/rig_sim.h"

namespace shapesense {
namespace {

TEST(ParseOutage, TakesACameraByNameOrIndex) {
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  const Outage by_name = ParseOutage("cam1:5:2.5", rig);
  EXPECT_EQ(by_name.camera, 1);
  EXPECT_DOUBLE_EQ(by_name.start_s, 5.0);
  EXPECT_DOUBLE_EQ(by_name.duration_s, 2.5);
  EXPECT_EQ(ParseOutage("2:0:1", rig).camera, 2);
}

TEST(ParseOutage, RejectsWhatItCannotRead) {
  const Rig rig = MakeSyntheticRig(SyntheticRigOptions{});
  for (const std::string spec : {"cam1:5", "cam9:1:1", "cam1:x:1", "cam1:1:0", "cam1:-1:2"}) {
    try {
      ParseOutage(spec, rig);
      ADD_FAILURE() << spec << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(spec), std::string::npos) << e.what();
    }
  }
}

TEST(RunRigSim, BadOptionsFailBeforeAnythingIsServed) {
  const std::atomic<bool> stop{true};
  const auto message = [&](const RigSimArgs& args) -> std::string {
    try {
      RunRigSim(args, stop);
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no InputError)";
  };
  RigSimArgs args;
  args.packet_loss = 1.5;
  EXPECT_NE(message(args).find("--packet-loss"), std::string::npos) << message(args);
  args = RigSimArgs{};
  args.ips = {"127.0.0.1"};
  EXPECT_NE(message(args).find("--ips"), std::string::npos) << message(args);
  args = RigSimArgs{};
  args.fault_camera = "cam7";
  EXPECT_NE(message(args).find("--fault-camera"), std::string::npos) << message(args);
  args = RigSimArgs{};
  args.trajectory_path = "/nonexistent/trajectory.yaml";
  EXPECT_NE(message(args).find("/nonexistent/trajectory.yaml"), std::string::npos) << message(args);
}

}  // namespace
}  // namespace shapesense
