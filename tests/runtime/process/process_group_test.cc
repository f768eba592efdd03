// Running a group of programs (stand-ins written in sh): up when their line
// or status shows, one-off jobs waited for, every failure named with the
// program's last output, Ctrl-C honoured while waiting, and the programs
// stopped last-started-first.
#include "runtime/process/process_group.h"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using std::chrono::seconds;

// Runs until SIGTERM, then ends well, as the services do.
constexpr const char* kEndsOnTerm = "trap 'exit 0' TERM; echo up; while :; do sleep 0.05; done";

ProgramSpec Sh(const std::string& name, const std::string& script) {
  return {name, {"/bin/sh", "-c", script}, "", "", false};
}

// Up once its trap is set.
ProgramSpec EndsOnTerm(const std::string& name) {
  ProgramSpec process = Sh(name, kEndsOnTerm);
  process.ready_line = "up";
  return process;
}

class ProcessGroupTest : public ::testing::Test {
 protected:
  void SetUp() override {
    logs_ = fs::path(::testing::TempDir()) / ("process_group_test_" + std::to_string(getpid()));
    fs::remove_all(logs_);
  }
  void TearDown() override { fs::remove_all(logs_); }

  ProcessGroup::Hooks Hooks() {
    return {[](int) {}, [this](const std::string& s) { return statuses_.contains(s); }};
  }

  // The message of the ProgramFailure `start` throws ("" when none).
  static std::string FailureOf(const std::function<void()>& start) {
    try {
      start();
    } catch (const ProgramFailure& e) {
      return e.what();
    }
    return "";
  }

  fs::path logs_;
  std::atomic<bool> stop_{false};
  std::set<std::string> statuses_;
};

TEST_F(ProcessGroupTest, UpWhenItsLineOrStatusShows) {
  ProcessGroup processes(logs_, stop_, Hooks());
  ProgramSpec lined = Sh("lined", "sleep 0.2; echo 'it is ready now'; exec sleep 30");
  lined.ready_line = "ready now";
  EXPECT_TRUE(processes.Start(lined, seconds(30)));
  ProgramSpec service = Sh("service", "exec sleep 30");
  service.ready_status = "carving";
  statuses_.insert("carving");
  EXPECT_TRUE(processes.Start(service, seconds(30)));
  processes.CheckRunning();
  EXPECT_TRUE(fs::exists(logs_ / "lined.log"));
}

TEST_F(ProcessGroupTest, AnEarlyEndIsNamedWithItsLastOutput) {
  ProcessGroup processes(logs_, stop_, Hooks());
  ProgramSpec broken = Sh("carving", "echo 'rig.yaml: expected a rig' >&2; exit 2");
  broken.ready_status = "carving";
  const std::string message = FailureOf([&] { processes.Start(broken, seconds(30)); });
  EXPECT_NE(message.find("carving"), std::string::npos) << message;
  EXPECT_NE(message.find("exited with status 2"), std::string::npos) << message;
  EXPECT_NE(message.find("rig.yaml: expected a rig"), std::string::npos) << message;
  EXPECT_NE(message.find((logs_ / "carving.log").string()), std::string::npos) << message;
}

TEST_F(ProcessGroupTest, OneOffJobsAreWaitedForAndTheirFailureNamed) {
  ProcessGroup processes(logs_, stop_, Hooks());
  ProgramSpec job = Sh("background", "sleep 0.2; echo written");
  job.runs_to_end = true;
  EXPECT_TRUE(processes.Start(job, seconds(30)));
  ASSERT_EQ(processes.ends().size(), 1u);
  EXPECT_TRUE(processes.ends()[0].clean);
  ProgramSpec failing = Sh("background2", "echo 'no frame for 5 s' >&2; exit 1");
  failing.runs_to_end = true;
  const std::string message = FailureOf([&] { processes.Start(failing, seconds(30)); });
  EXPECT_NE(message.find("no frame for 5 s"), std::string::npos) << message;
}

TEST_F(ProcessGroupTest, NeverUpIsAFailureAndStopEndsTheWait) {
  ProcessGroup processes(logs_, stop_, Hooks());
  ProgramSpec silent = Sh("silent", "exec sleep 30");
  silent.ready_line = "ready";
  const std::string message = FailureOf([&] { processes.Start(silent, seconds(1)); });
  EXPECT_NE(message.find("did not come up"), std::string::npos) << message;
  EXPECT_NE(message.find("printed nothing"), std::string::npos) << message;
  stop_ = true;  // Ctrl-C while waiting
  ProgramSpec waiting = Sh("waiting", "exec sleep 30");
  waiting.ready_line = "never";
  EXPECT_FALSE(processes.Start(waiting, seconds(30)));
}

TEST_F(ProcessGroupTest, AProgramThatEndsWhileRunningIsNamed) {
  ProcessGroup processes(logs_, stop_, Hooks());
  EXPECT_TRUE(processes.Start(EndsOnTerm("steady"), seconds(30)));
  EXPECT_TRUE(processes.Start(Sh("crashing", "sleep 0.3; echo 'out of memory'; kill -SEGV $$"),
                              seconds(30)));
  std::string message;
  for (int i = 0; i < 300 && message.empty(); ++i) {
    message = FailureOf([&] { processes.CheckRunning(); });
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_NE(message.find("crashing"), std::string::npos) << message;
  EXPECT_NE(message.find("signal 11"), std::string::npos) << message;
  EXPECT_NE(message.find("out of memory"), std::string::npos) << message;
}

// The stand-in for systemd's Restart=on-failure: a program killed outright
// is started again, its end recorded, its output kept in the same log.
TEST_F(ProcessGroupTest, AProgramToRestartIsStartedAgainAfterItsEnd) {
  ProcessGroup processes(logs_, stop_, Hooks());
  ProgramSpec flaky = EndsOnTerm("flaky");
  flaky.argv.back() = "echo \"started $$\"; " + flaky.argv.back();
  flaky.restart = true;
  ASSERT_TRUE(processes.Start(flaky, seconds(30)));
  processes.Signal("flaky", SIGKILL);
  for (int i = 0; i < 500 && processes.restarts("flaky") == 0; ++i) {
    EXPECT_EQ(FailureOf([&] { processes.CheckRunning(); }), "");
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(processes.restarts("flaky"), 1);
  EXPECT_GT(processes.last_restart_utime("flaky"), 0);
  ASSERT_EQ(processes.ends().size(), 1u);
  EXPECT_NE(processes.ends()[0].how.find("signal 9"), std::string::npos) << processes.ends()[0].how;
  EXPECT_NE(processes.ends()[0].how.find("restarted"), std::string::npos);
  EXPECT_TRUE(processes.IsRunning("flaky"));
  EXPECT_TRUE(processes.Stop("flaky").clean);
  // Both runs printed into the one log.
  std::ifstream log(logs_ / "flaky.log");
  std::ostringstream read;
  read << log.rdbuf();
  const std::string text = read.str();
  size_t starts = 0;
  for (size_t at = text.find("started"); at != std::string::npos; at = text.find("started", at + 1))
    ++starts;
  EXPECT_EQ(starts, 2u) << text;
}
// As systemd's start limit: a program that keeps ending is a failure.
TEST_F(ProcessGroupTest, AProgramThatKeepsEndingIsAFailureAfterFiveRestarts) {
  ProcessGroup processes(logs_, stop_, Hooks());
  ProgramSpec crashing = Sh("crashing", "echo up; sleep 0.05; exit 3");
  crashing.ready_line = "up";
  crashing.restart = true;
  ASSERT_TRUE(processes.Start(crashing, seconds(30)));
  std::string message;
  for (int i = 0; i < 1000 && message.empty(); ++i) {
    message = FailureOf([&] { processes.CheckRunning(); });
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(processes.restarts("crashing"), 5);
  EXPECT_NE(message.find("after 5 restarts"), std::string::npos) << message;
}

TEST_F(ProcessGroupTest, StoppedLastStartedFirst) {
  std::vector<std::string> names = {"rig-sim", "lcm-logger", "carving", "shape", "capture"};
  {
    ProcessGroup processes(logs_, stop_, Hooks());
    for (const std::string& name : names) {
      ASSERT_TRUE(processes.Start(EndsOnTerm(name), seconds(30)));
    }
    EXPECT_TRUE(processes.Stop("capture").clean);
    processes.StopAll();
    std::vector<std::string> order;
    for (const ProgramEnd& end : processes.ends()) order.push_back(end.name);
    EXPECT_EQ(order, std::vector<std::string>(names.rbegin(), names.rend()));
  }
}

TEST(FindOnPathTest, FindsWhatIsOnThePathOnly) {
  EXPECT_FALSE(FindOnPath("sh").empty());
  EXPECT_TRUE(FindOnPath("no-such-program-anywhere").empty());
}

}  // namespace
}  // namespace shapesense
