// The live demo's plan of programs: for any rig size, rate and duration,
// every program talks on one LCM URL, the capture service reads exactly the
// cameras the rig-sim serves (or the simulated cameras of a config the
// capture service itself accepts), the services use the rig and backgrounds
// the first phase makes, and no program can outlive the demo.
#include "clients/tools/demo/demo_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>

#include "runtime/lcm/image_buses.h"
#include "services/capture/capture_options.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;

// The value after `flag` in `argv`, every time it appears.
std::vector<std::string> ValuesOf(const std::vector<std::string>& argv, const std::string& flag) {
  std::vector<std::string> values;
  for (size_t i = 0; i + 1 < argv.size(); ++i) {
    if (argv[i] == flag) values.push_back(argv[i + 1]);
  }
  return values;
}

std::string ValueOf(const std::vector<std::string>& argv, const std::string& flag) {
  const std::vector<std::string> values = ValuesOf(argv, flag);
  if (values.size() == 1) return values[0];
  return std::to_string(values.size()) + " values of " + flag;
}

bool Has(const std::vector<std::string>& argv, const std::string& arg) {
  return std::find(argv.begin(), argv.end(), arg) != argv.end();
}

const ProgramSpec& Find(const std::vector<ProgramSpec>& list, const std::string& name) {
  const auto found =
      std::find_if(list.begin(), list.end(), [&](const ProgramSpec& p) { return p.name == name; });
  if (found == list.end()) throw std::runtime_error("no process " + name);
  return *found;
}

std::vector<std::string> Names(const std::vector<ProgramSpec>& list) {
  std::vector<std::string> names;
  names.reserve(list.size());
  for (const ProgramSpec& p : list) names.push_back(p.name);
  return names;
}

// Random settings: 1-6 cameras, rates and durations over their range.
DemoSettings RandomSettings(std::mt19937& random, DemoCameras cameras) {
  DemoSettings settings;
  settings.bin_dir = "/opt/shapesense/bin";
  settings.lcm_logger = "/usr/bin/lcm-logger";
  settings.out = "/tmp/demo out";  // a space: arguments are never split
  settings.cameras = cameras;
  const int count = std::uniform_int_distribution<int>(1, 6)(random);
  for (int i = 0; i < count; ++i) settings.camera_names.push_back("cam" + std::to_string(i * 3));
  settings.rate_hz = std::uniform_real_distribution<double>(1.0, 300.0)(random);
  settings.duration_s = std::uniform_real_distribution<double>(0.5, 3600.0)(random);
  settings.seed = static_cast<uint32_t>(random());
  return settings;
}

// The --camera NAME=aravis:ADDRESS flags as (name, address) pairs.
std::vector<std::pair<std::string, std::string>> AravisCameras(
    const std::vector<std::string>& argv) {
  std::vector<std::pair<std::string, std::string>> cameras;
  for (const std::string& spec : ValuesOf(argv, "--camera")) {
    const size_t equals = spec.find("=aravis:");
    if (equals == std::string::npos) throw std::runtime_error("not aravis: " + spec);
    cameras.emplace_back(spec.substr(0, equals), spec.substr(equals + 8));
  }
  return cameras;
}

void ExpectEveryProgramEndsByItself(const DemoPlan& plan, const DemoSettings& settings) {
  for (const auto* list : {&plan.background, &plan.pipeline}) {
    for (const ProgramSpec& p : *list) {
      // A logger is stopped by the demo, a job ends by itself.
      if (p.name.rfind("lcm-logger", 0) == 0 || p.runs_to_end) continue;
      EXPECT_GT(std::stod(ValueOf(p.argv, "--duration")), settings.duration_s + 60.0) << p.name;
    }
  }
}

TEST(DemoPlanTest, GigEPipelineReadsExactlyTheCamerasTheRigSimServes) {
  std::mt19937 random(11);
  for (int trial = 0; trial < 20; ++trial) {
    const DemoSettings settings = RandomSettings(random, DemoCameras::kGigE);
    const DemoPlan plan = MakeDemoPlan(settings);
    const ProgramSpec& rig_sim = Find(plan.pipeline, "rig-sim");
    const ProgramSpec& capture = Find(plan.pipeline, "capture");
    std::string addresses;
    const auto cameras = AravisCameras(capture.argv);
    ASSERT_EQ(cameras.size(), settings.camera_names.size());
    for (size_t i = 0; i < cameras.size(); ++i) {
      EXPECT_EQ(cameras[i].first, settings.camera_names[i]);
      if (i > 0) addresses += ',';
      addresses += cameras[i].second;
    }
    EXPECT_EQ(ValueOf(rig_sim.argv, "--ips"), addresses);
    EXPECT_EQ(ValueOf(rig_sim.argv, "--rig"), plan.rig.string());
    EXPECT_EQ(std::stod(ValueOf(capture.argv, "--rate")), settings.rate_hz);
    EXPECT_FALSE(Has(rig_sim.argv, "--backdrop-only"));
    EXPECT_EQ(rig_sim.ready_line, "rig-sim: ready");
    ExpectEveryProgramEndsByItself(plan, settings);
  }
}

TEST(DemoPlanTest, BackgroundsComeFromTheBackdropAloneBeforeThePipeline) {
  std::mt19937 random(12);
  for (const DemoCameras cameras : {DemoCameras::kGigE, DemoCameras::kSimulated}) {
    const DemoSettings settings = RandomSettings(random, cameras);
    const DemoPlan plan = MakeDemoPlan(settings);
    ASSERT_FALSE(plan.background.empty());
    const ProgramSpec& job = plan.background.back();
    EXPECT_TRUE(job.runs_to_end);
    EXPECT_EQ(ValueOf(job.argv, "--out"), plan.backgrounds.string());
    EXPECT_TRUE(Has(job.argv, "background"));
    if (cameras == DemoCameras::kGigE) {
      EXPECT_TRUE(Has(Find(plan.background, "rig-sim-backdrop").argv, "--backdrop-only"));
      EXPECT_EQ(AravisCameras(job.argv).size(), settings.camera_names.size());
    }
    for (const char* service : {"carving", "shape"}) {
      const ProgramSpec& p = Find(plan.pipeline, service);
      EXPECT_EQ(ValueOf(p.argv, "--rig"), plan.rig.string());
      EXPECT_EQ(p.ready_status, service) << "up once its status is on LCM";
    }
    // The carving service makes the silhouettes; the shape service gets them from it.
    EXPECT_EQ(ValueOf(Find(plan.pipeline, "carving").argv, "--backgrounds"),
              plan.backgrounds.string());
    EXPECT_FALSE(Has(Find(plan.pipeline, "shape").argv, "--backgrounds"));
  }
}

TEST(DemoPlanTest, EveryProgramOnTheRigsUrlEachCamerasImagesLoggedOnItsPort) {
  std::mt19937 random(13);
  for (const DemoCameras cameras : {DemoCameras::kGigE, DemoCameras::kSimulated}) {
    DemoSettings settings = RandomSettings(random, cameras);
    settings.lcm_url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=" + std::to_string(random());
    const DemoPlan plan = MakeDemoPlan(settings);
    const std::vector<std::string> names = Names(plan.pipeline);
    // Recording before any image; stopped (in reverse) after the last shape.
    EXPECT_LT(std::find(names.begin(), names.end(), "lcm-logger") - names.begin(),
              std::find(names.begin(), names.end(), "carving") - names.begin());
    EXPECT_EQ(names.back(), "capture");
    ASSERT_EQ(plan.image_logs.size(), settings.camera_names.size());
    for (size_t k = 0; k < settings.camera_names.size(); ++k) {
      const ProgramSpec& logger = Find(plan.pipeline, "lcm-logger-" + settings.camera_names[k]);
      EXPECT_TRUE(Has(logger.argv, "--lcm-url=" + ImageUrl(settings.lcm_url, k)));
      EXPECT_EQ(logger.argv.back(), plan.image_logs[k].string());
      EXPECT_LT(std::find(names.begin(), names.end(), logger.name) - names.begin(),
                std::find(names.begin(), names.end(), "capture") - names.begin());
    }
    for (const ProgramSpec& p : plan.pipeline) {
      if (p.name == "lcm-logger") {
        EXPECT_TRUE(Has(p.argv, "--lcm-url=" + settings.lcm_url));
        EXPECT_EQ(p.argv.back(), plan.log.string());
        continue;
      }
      if (p.name.rfind("lcm-logger-", 0) == 0) continue;
      EXPECT_EQ(ValueOf(p.argv, "--lcm-url"), settings.lcm_url) << p.name;
      EXPECT_EQ(fs::path(p.argv.front()).parent_path(), settings.bin_dir) << p.name;
    }
  }
}

// With a socket for it, the web monitor runs beside the services on that
// socket (made by the demo in the host's network), the shape projected
// through the demo's rig; without one, there is none.
TEST(DemoPlanTest, TheWebMonitorServesTheSocketItIsGiven) {
  std::mt19937 random(17);
  DemoSettings settings = RandomSettings(random, DemoCameras::kGigE);
  EXPECT_THROW(Find(MakeDemoPlan(settings).pipeline, "monitor"), std::runtime_error);
  settings.monitor_socket = 7;
  settings.shape_config = "/tmp/shape.yaml";
  const DemoPlan plan = MakeDemoPlan(settings);
  const ProgramSpec& monitor = Find(plan.pipeline, "monitor");
  EXPECT_EQ(monitor.listen_socket, 7);
  EXPECT_EQ(ValueOf(monitor.argv, "--calibration"), plan.rig.string());
  EXPECT_EQ(ValueOf(monitor.argv, "--shape-config"), "/tmp/shape.yaml");
  EXPECT_EQ(ValueOf(monitor.argv, "--lcm-url"), settings.lcm_url);
  EXPECT_FALSE(Has(monitor.argv, "--http")) << "it serves the socket it is given";
  EXPECT_GT(monitor.nice, 0) << "a view yields to the pipeline";
  const std::vector<std::string> names = Names(plan.pipeline);
  EXPECT_LT(std::find(names.begin(), names.end(), "monitor") - names.begin(),
            std::find(names.begin(), names.end(), "capture") - names.begin());
  for (const ProgramSpec& other : plan.pipeline) {
    if (other.name != "monitor") {
      EXPECT_EQ(other.listen_socket, -1) << other.name;
    }
  }
}

// The closed-loop experiment's plan: the rig-sim serves the plant, the shape
// service senses q, the logger leaves the images out, and each controller
// run is on the same network with its logs apart.
TEST(DemoPlanTest, PlantModeServesThePlantSensesQAndLogsNoImages) {
  std::mt19937 random(15);
  DemoSettings settings = RandomSettings(random, DemoCameras::kGigE);
  settings.plant_config = "/cfg/rig_plant.yaml";
  settings.shape_config = "/cfg/shape_service_plant.yaml";
  settings.log_channels = kControlChannels;
  const DemoPlan plan = MakeDemoPlan(settings);
  for (const ProgramSpec& p : plan.pipeline) {
    if (p.name == "rig-sim") {
      EXPECT_EQ(ValueOf(p.argv, "--plant"), settings.plant_config);
    } else if (p.name == "shape") {
      EXPECT_EQ(ValueOf(p.argv, "--config"), settings.shape_config);
    } else if (p.name == "carving") {
      EXPECT_FALSE(Has(p.argv, "--config"));
    } else if (p.name == "lcm-logger") {
      EXPECT_TRUE(Has(p.argv, std::string("--channel=") + kControlChannels));
    }
  }
  for (const ProgramSpec& p : plan.background) EXPECT_FALSE(Has(p.argv, "--plant")) << p.name;
  EXPECT_TRUE(plan.image_logs.empty()) << "no image logger when the channels are picked";
  for (const ProgramSpec& p : plan.pipeline) EXPECT_NE(p.name.rfind("lcm-logger-", 0), 0u);
  const std::regex logged(kControlChannels);
  for (const char* channel :
       {"SHAPESENSE_SHAPE", "SHAPESENSE_TRUTH", "SHAPESENSE_TARGET", "SHAPESENSE_TENDON_COMMAND",
        "SHAPESENSE_PLANT_STATE", "SHAPESENSE_STATUS_controller", "SHAPESENSE_ESTOP"}) {
    EXPECT_TRUE(std::regex_match(channel, logged)) << channel;
  }
  for (const char* channel :
       {"SHAPESENSE_IMAGE_cam0", "SHAPESENSE_VOXELS", "SHAPESENSE_SILHOUETTE_cam0"}) {
    EXPECT_FALSE(std::regex_match(channel, logged)) << channel;
  }
  const ProgramSpec run = ControllerRun(settings, "/cfg/controller_client.yaml", "closed_loop",
                                        settings.out / "closed_loop");
  EXPECT_EQ(ValueOf(run.argv, "--mode"), "closed_loop");
  EXPECT_EQ(ValueOf(run.argv, "--targets"), "stream");
  EXPECT_EQ(ValueOf(run.argv, "--lcm-url"), settings.lcm_url);
  EXPECT_EQ(ValueOf(run.argv, "--log-csv"),
            (settings.out / "closed_loop" / "controller_log.csv").string());
  EXPECT_EQ(run.ready_status, "controller");
}

TEST(DemoPlanTest, SimulatedCamerasNeedNoRigSimAndTheirConfigIsValid) {
  std::mt19937 random(14);
  const fs::path dir = fs::path(::testing::TempDir()) / "demo_plan_test";
  fs::create_directories(dir);
  for (int trial = 0; trial < 10; ++trial) {
    const DemoSettings settings = RandomSettings(random, DemoCameras::kSimulated);
    const DemoPlan plan = MakeDemoPlan(settings);
    for (const auto* list : {&plan.background, &plan.pipeline}) {
      for (const ProgramSpec& p : *list) EXPECT_EQ(p.name.find("rig-sim"), std::string::npos);
    }
    EXPECT_EQ(ValueOf(Find(plan.pipeline, "capture").argv, "--config"),
              plan.capture_config.string());
    const fs::path config = dir / "capture.yaml";
    std::ofstream(config) << plan.capture_config_text;
    const CaptureServiceOptions options = LoadCaptureOptions(config.string(), {});
    ASSERT_EQ(options.cameras.size(), settings.camera_names.size());
    for (size_t i = 0; i < options.cameras.size(); ++i) {
      EXPECT_EQ(options.cameras[i].name, settings.camera_names[i]);
      EXPECT_EQ(options.cameras[i].backend, "simulated");
    }
    EXPECT_EQ(options.rig, plan.rig.string());
    EXPECT_EQ(options.trigger_rate_hz, settings.rate_hz);
    EXPECT_EQ(options.simulation.seed, settings.seed);
  }
  fs::remove_all(dir);
}

TEST(DemoPlanTest, OutputsStayInTheOutputFolder) {
  std::mt19937 random(15);
  const DemoSettings settings = RandomSettings(random, DemoCameras::kGigE);
  const DemoPlan plan = MakeDemoPlan(settings);
  for (const fs::path& path :
       {plan.rig, plan.backgrounds, plan.log, plan.logs_dir, plan.report, plan.replay_shapes}) {
    const std::string relative = fs::relative(path, settings.out).string();
    EXPECT_FALSE(relative.starts_with("..")) << path;
  }
}

TEST(MissingProgramsTest, NamesEveryMissingProgramWithWhatToDo) {
  DemoPlan plan;
  plan.background.push_back({"a", {"/bin/sh"}, "", "", true});
  plan.pipeline.push_back({"b", {"/nonexistent/bin/shapesense-carving"}, "", "", false});
  plan.pipeline.push_back({"c", {"/nonexistent/lcm-logger"}, "", "", false});
  plan.pipeline.push_back({"d", {"/nonexistent/bin/shapesense-carving"}, "", "", false});
  const std::vector<std::string> missing = MissingPrograms(plan);
  ASSERT_EQ(missing.size(), 2u);
  EXPECT_NE(missing[0].find("shapesense-carving is missing; build it"), std::string::npos);
  EXPECT_NE(missing[1].find("lcm-logger is missing; install it: apt-get install liblcm-bin"),
            std::string::npos);
}

}  // namespace
}  // namespace shapesense
