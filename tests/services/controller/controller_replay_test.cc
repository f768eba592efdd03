// Replay protection end to end (docs/security.md): a run's targets, shapes
// and plant traffic, recorded by lcm-logger, are played back with
// lcm-logplayer into a live controller on the same multicast group, with
// the same key and the same sender names. The controller is the in-process
// rig over real UDP multicast with the rig key, stepped deterministically
// (each step hands over what it published up to a barrier), so a run can
// be compared command by command with the same run without the replay:
// none of the replayed messages is accepted, each is counted as a replay
// or too old, and every tendon command is identical.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <thread>

#include "runtime/host_clock.h"
#include "runtime/lcm/channels.h"
#include "runtime/process/child_process.h"
#include "shapesense/configuration_target_t.hpp"
#include "shapesense/header_t.hpp"
#include "shapesense/tendon_state_t.hpp"
#include "tests/runtime/lcm/temporary_key_file.h"
#include "tests/services/controller/in_process_rig.h"
#include "tests/support/network_test.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using std::chrono::milliseconds;
using testing::InProcessRig;

constexpr const char* kUrl = "udpm://239.255.79.3:7931?ttl=0";
constexpr const char* kLoggerUrl = "udpm://239.255.79.3:7931?ttl=0&recv_buf_size=4194304";
constexpr int kTargetStep = 25;
constexpr int kSteps = 400;

struct Step {
  Eigen::VectorXd command;
  int8_t mode = 0;
  int64_t sensed_trigger_seq = -1;
  bool operator==(const Step& other) const {
    return command == other.command && mode == other.mode &&
           sensed_trigger_seq == other.sensed_trigger_seq;
  }
};

configuration_target_t Target(double kappa_x, double kappa_z) {
  configuration_target_t target{};
  target.kind = configuration_target_t::KIND_CONFIGURATION;
  target.q[0] = kappa_x;
  target.q[1] = kappa_z;
  target.q[3] = 0.004;
  target.duration_s = 1.0;
  target.source = "test";
  return target;
}

testing::FakeRigOptions Rig() {
  testing::FakeRigOptions rig;
  rig.plant = testing::OffNominalPlant();
  return rig;
}

class ControllerReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(nettest::PrivateNetworkError(), "");
    dir_ = fs::path(::testing::TempDir()) / ("controller_replay_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // The bus of every run: the rig key, and the same sender name in every
  // run, as a restarted program has.
  LcmBusOptions Bus() const {
    LcmBusOptions options;
    options.url = kUrl;
    options.auth.key_files = {key_.path()};
    options.auth.sender = "control/shapesense-controller";
    return options;
  }

  // A closed-loop run towards `target`, streamed at kTargetStep;
  // `after_target` runs once that step is done.
  std::vector<Step> Run(const std::string& name, const configuration_target_t& target,
                        const std::function<void(InProcessRig&)>& after_target = {},
                        AuthCounts* auth = nullptr) {
    const fs::path logs = dir_ / name;
    fs::create_directories(logs);
    InProcessRig rig(testing::StreamSetup(ControlMode::kClosedLoop, logs), Rig(), Bus());
    rig.Start();
    std::vector<Step> steps;
    for (int i = 0; i < kSteps && !rig.client().finished(); ++i) {
      if (i == kTargetStep) {
        EXPECT_TRUE(rig.bus().Publish(channels::kTarget, target));
      }
      rig.Step();
      const StepRecord& step = rig.client().last_step();
      steps.push_back({step.command, step.mode, step.sensed_trigger_seq});
      if (i == kTargetStep && after_target) after_target(rig);
    }
    if (auth != nullptr) *auth = rig.bus().AuthSnapshot();
    return steps;
  }

  static std::unique_ptr<ChildProcess> Start(const std::vector<std::string>& argv) {
    return std::make_unique<ChildProcess>(argv);
  }

  fs::path dir_;
  test_keys::TemporaryKeyFile key_;
};

// Sees the replay on the group: a signed message whose counter is below the
// live run's start (it was signed in the recorded run).
class ReplayTap {
 public:
  explicit ReplayTap(int64_t live_start) : live_start_(live_start), lcm_(kUrl) {
    for (const char* channel : {channels::kShape, channels::kPlantState}) {
      lcm_.subscribeFunction(channel, &ReplayTap::OnMessage, this);
    }
  }
  bool WaitForReplay(milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (!seen_ && std::chrono::steady_clock::now() < end) lcm_.handleTimeout(10);
    return seen_;
  }

 private:
  static void OnMessage(const lcm::ReceiveBuffer* buffer, const std::string&, ReplayTap* self) {
    header_t header;
    constexpr int kFingerprint = 8;
    if (header._decodeNoHash(buffer->data, kFingerprint,
                             static_cast<int>(buffer->data_size) - kFingerprint) < 0) {
      return;
    }
    if (!header.auth.sender.empty() && header.auth.counter < self->live_start_) self->seen_ = true;
  }

  int64_t live_start_;
  lcm::LCM lcm_;
  bool seen_ = false;
};

// Publishes probes until lcm-logger has written one: it is subscribed.
void WaitUntilLogging(const fs::path& log) {
  LcmBus probe(kUrl);
  tendon_state_t marker{};
  for (int i = 0; i < 200; ++i) {
    probe.Publish("TEST_LOGGER_PROBE", marker);
    std::this_thread::sleep_for(milliseconds(50));
    std::error_code error;
    if (fs::file_size(log, error) > 0 && !error) return;
  }
  FAIL() << "lcm-logger wrote nothing to " << log << " within 10 s";
}

bool LogHasChannel(const fs::path& log, const std::string& channel) {
  lcm::LogFile file(log.string(), "r");
  if (!file.good()) return false;
  for (const lcm::LogEvent* event = file.readNextEvent(); event != nullptr;
       event = file.readNextEvent()) {
    if (event->channel == channel) return true;
  }
  return false;
}

// Publishes an end marker until lcm-logger has written it: everything sent
// before it on the group has then been read and written too (one socket
// receives in order), so stopping the logger loses nothing of the run.
void WaitUntilLogged(const fs::path& log) {
  LcmBus probe(kUrl);
  tendon_state_t marker{};
  for (int i = 0; i < 200; ++i) {
    probe.Publish("TEST_LOGGER_END", marker);
    std::this_thread::sleep_for(milliseconds(50));
    if (LogHasChannel(log, "TEST_LOGGER_END")) return;
  }
  FAIL() << "lcm-logger did not write the end marker to " << log << " within 10 s";
}

// Signed messages of the log on the channels the rig's controller and plant verify.
int64_t ReplayableMessages(const fs::path& log) {
  lcm::LogFile file(log.string(), "r");
  int64_t count = 0;
  for (const lcm::LogEvent* event = file.readNextEvent(); event != nullptr;
       event = file.readNextEvent()) {
    for (const char* channel :
         {channels::kTarget, channels::kShape, channels::kPlantState, channels::kPlantCommand}) {
      count += event->channel == channel ? 1 : 0;
    }
  }
  return count;
}

TEST_F(ControllerReplayTest, ARecordedRunPlayedIntoALiveControllerIsRejectedAndChangesNoCommand) {
  // A run towards one target, recorded.
  const fs::path log = dir_ / "recorded.lcmlog";
  // The in-process rig runs as fast as it can: the whole run (~0.6 MB) must
  // fit the logger's socket buffer, or a logger the machine's load keeps
  // off the CPU for a moment drops what the run sent meanwhile.
  auto logger = Start({"/usr/bin/lcm-logger", "--lcm-url=" + std::string(kLoggerUrl),
                       "--flush-interval=50", "--force", log.string()});
  WaitUntilLogging(log);
  Run("recorded", Target(0.004, 0.0));
  WaitUntilLogged(log);
  logger->Stop(SIGINT, milliseconds(5000));
  const int64_t replayable = ReplayableMessages(log);
  ASSERT_GT(replayable, kSteps) << "the recording holds the run's shapes, states and commands";

  // Another run towards another target, alone, then with the recording
  // played into it once its target is in: the replay starts while the
  // controller runs, and the run waits until the first replayed message
  // has been refused.
  AuthCounts alone_auth;
  const std::vector<Step> alone = Run("alone", Target(0.0, 0.004), {}, &alone_auth);
  std::unique_ptr<ChildProcess> player;
  AuthCounts replayed_auth;
  const int64_t replayed_start = HostUtime();
  const std::vector<Step> replayed = Run(
      "replayed", Target(0.0, 0.004),
      [&](InProcessRig&) {
        ReplayTap tap(replayed_start);
        player = Start({"/usr/bin/lcm-logplayer", "--lcm-url=" + std::string(kUrl), log.string()});
        // Once a replayed message is on the group, it waits in the rig's
        // socket too (the kernel hands a datagram to every member at once),
        // ahead of the next step's barrier. The rig's own bus is not
        // handled meanwhile: its steps stay as they are without the replay.
        ASSERT_TRUE(tap.WaitForReplay(milliseconds(10000))) << "nothing replayed within 10 s";
      },
      &replayed_auth);
  if (player) player->Stop(SIGTERM, milliseconds(2000));

  ASSERT_EQ(replayed.size(), alone.size());
  for (size_t i = 0; i < alone.size(); ++i) {
    ASSERT_TRUE(replayed[i] == alone[i]) << "step " << i << ": the command differs";
  }
  // None was accepted: the run with the replay accepted exactly what the
  // run alone did. Every refusal is a replay or too old, none a forgery.
  EXPECT_EQ(replayed_auth.accepted, alone_auth.accepted);
  EXPECT_TRUE(alone_auth.rejections.empty());
  int64_t refused = 0;
  for (const auto& [reason, count] : replayed_auth.rejections) {
    EXPECT_TRUE(reason == "too_old" || reason == "replayed") << reason;
    refused += count;
  }
  EXPECT_GT(refused, 0);
  EXPECT_LE(refused, replayable);
  std::cout << "replayed " << replayable
            << " recorded messages; refused while the run lasted: " << refused << " (too_old "
            << replayed_auth.rejections["too_old"] << ", replayed "
            << replayed_auth.rejections["replayed"] << ")" << std::endl;
}

}  // namespace
}  // namespace shapesense
