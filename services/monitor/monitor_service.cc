#include "services/monitor/monitor_service.h"

#include <openssl/crypto.h>
#include <sys/stat.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include "libs/core/error.h"
#include "libs/mechanics/base_pose.h"
#include "libs/mechanics/manipulator_options.h"
#include "runtime/config_file.h"
#include "runtime/file_io.h"
#include "runtime/host_clock.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/pipeline_stages.h"
#include "runtime/lcm/service_loop.h"
#include "runtime/lcm/service_status.h"
#include "runtime/lcm/shape_message.h"
#include "runtime/lcm/voxel_cloud_message.h"
#include "runtime/process/systemd_notify.h"
#include "runtime/rig/rig_file.h"
#include "services/monitor/monitor_model.h"
#include "services/monitor/web_server.h"

namespace shapesense {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int64_t kTickUs = 250'000;  // health and statistics, 4 Hz
constexpr size_t kMinTokenLength = 16;
constexpr int32_t kMaxPreviewBytes = 256 * 1024;  // a preview is tens of kB

fs::path DefaultAssets() {
  std::error_code error;
  const fs::path exe = fs::read_symlink("/proc/self/exe", error);
  return exe.parent_path().parent_path() / "share" / "shapesense" / "monitor";
}

std::string PreviewProblem(const image_t& preview) {
  if (preview.compression != image_t::COMPRESSION_JPEG) return "preview not JPEG";
  if (preview.size > kMaxPreviewBytes || preview.size < 4) return "preview of an impossible size";
  if (preview.data[0] != 0xff || preview.data[1] != 0xd8) return "preview not a JPEG";
  return "";
}

// What the monitor knows of the rig from its files.
struct MonitorSetup {
  std::vector<Camera> cameras;
  std::optional<RigFile> rig;
  std::optional<TargetGeometry> geometry;
  std::string token;
};

std::array<double, 3> Triple(const YAML::Node& node, const std::string& key) {
  std::array<double, 3> value = {0.0, 0.0, 0.0};
  if (node[key]) value = node[key].as<std::array<double, 3>>();
  return value;
}

// From the shape service's config (config/shape_service.yaml; read here, as
// a service includes no other's code): its rig file, and with
// configuration.enabled the manipulator's rest lengths and base pose.
std::optional<TargetGeometry> ReadShapeConfig(const fs::path& file, fs::path* calibration) {
  try {
    const YAML::Node root = YAML::Load(ReadTextFile(file));
    if (root["rig"] && calibration->empty()) {
      *calibration = ResolveConfigPath(file, root["rig"].as<std::string>());
    }
    const YAML::Node section = root["configuration"];
    if (!section || !section["enabled"] || !section["enabled"].as<bool>()) return std::nullopt;
    const fs::path model_file = ResolveConfigPath(file, section["manipulator"].as<std::string>());
    const ManipulatorOptions model =
        ParseManipulatorYaml(ReadTextFile(model_file), model_file.string());
    BasePose base;
    base.base_position = Triple(section, "base_position");
    base.base_rotation = Triple(section, "base_rotation");
    return TargetGeometry{{model.proximal_length, model.distal_length}, base.WorldFromBase()};
  } catch (const YAML::Exception& e) {
    throw InputError(file.string() + ": " + e.what());
  }
}

MonitorSetup LoadSetup(const MonitorArgs& args) {
  MonitorSetup setup;
  fs::path calibration = args.calibration;
  if (!args.shape_config.empty()) setup.geometry = ReadShapeConfig(args.shape_config, &calibration);
  if (!calibration.empty()) setup.cameras = LoadRigSetup(calibration, {}).rig.cameras;
  if (!args.rig.empty()) setup.rig = ParseRigFile(ReadTextFile(args.rig), args.rig);
  if (!args.estop_token_file.empty()) setup.token = ReadEstopToken(args.estop_token_file);
  return setup;
}

// The bus side: each message into the model, each update out to the browsers.
class MonitorService {
 public:
  MonitorService(MonitorModel& model, WebServer& web, ServiceStatus& status)
      : model_(model), web_(web), status_(status) {}

  void Subscribe(LcmBus& bus) {
    On<shape_t>(bus, channels::kShape, [this](const shape_t& shape, int64_t received) {
      if (const std::string why = ValidateShapeMessage(shape); !why.empty()) throw Malformed(why);
      return model_.OnShape(shape, received);
    });
    On<shape_t>(bus, channels::kTruth,
                [this](const shape_t& truth, int64_t) { return model_.OnTruth(truth); });
    On<silhouettes_t>(bus, channels::kSilhouettes,
                      [this](const silhouettes_t& set, int64_t received) {
                        return model_.OnSilhouettes(set, received);
                      });
    On<voxel_cloud_t>(bus, channels::kVoxels, [this](const voxel_cloud_t& cloud, int64_t) {
      if (const std::string why = ValidateVoxelCloudMessage(cloud); !why.empty()) {
        throw Malformed(why);
      }
      return model_.OnVoxels(cloud);
    });
    On<image_t>(bus, channels::kPreviewPattern, [this](image_t& preview, int64_t) {
      if (const std::string why = PreviewProblem(preview); !why.empty()) throw Malformed(why);
      return model_.OnPreview(std::move(preview));
    });
    On<service_status_t>(bus, channels::kStatusPattern,
                         [this](const service_status_t& status, int64_t received) {
                           return model_.OnStatus(status, received);
                         });
    On<configuration_target_t>(
        bus, channels::kTarget,
        [this](const configuration_target_t& target, int64_t) { return model_.OnTarget(target); });
    On<tendon_command_t>(bus, channels::kTendonCommand,
                         [this](const tendon_command_t& command, int64_t) {
                           return model_.OnTendonCommand(command);
                         });
    On<tendon_state_t>(bus, channels::kTendonState, [this](const tendon_state_t& state, int64_t) {
      return model_.OnTendonState(state);
    });
    On<estop_t>(bus, channels::kEstop,
                [this](const estop_t& estop, int64_t) { return model_.OnEstop(estop); });
  }

  void Poll(LcmBus& bus, int64_t now) {
    if (now >= next_tick_) {
      Send(model_.Tick(now));
      next_tick_ = now + kTickUs;
    }
    const WebServerCounters web = web_.Counters();
    status_.Published(web.messages_sent - counted_sent_);
    counted_sent_ = web.messages_sent;
    status_.SetQueueDepth(static_cast<int>(web.clients));
    status_.MaybePublish(bus, now);
  }

 private:
  struct Malformed : std::runtime_error {
    using std::runtime_error::runtime_error;
  };

  // A handler that turns one message into web updates; a malformed message
  // is counted, never shown.
  template <class Message, class Handler>
  void On(LcmBus& bus, const std::string& channel, Handler handler) {
    bus.Subscribe<Message>(
        channel, [this, handler](Message&& message, const std::string&, int64_t received) {
          status_.Received();
          try {
            Send(handler(message, received));
          } catch (const Malformed& e) {
            status_.Rejected();
            status_.Note(e.what());
          }
        });
  }

  void Send(std::vector<WebUpdate> updates) {
    for (WebUpdate& update : updates) {
      const WebMessage message{std::make_shared<const std::string>(std::move(update.payload)),
                               update.binary, update.utime};
      web_.Publish(update.channel, message);
      if (!update.foxglove_channel.empty()) web_.Publish(update.foxglove_channel, message);
    }
  }

  MonitorModel& model_;
  WebServer& web_;
  ServiceStatus& status_;
  int64_t next_tick_ = 0;
  int64_t counted_sent_ = 0;
};

// JSON Schemas of what Foxglove clients are sent: the page's own messages
// (docs/monitor.md describes their fields), loosely (extra fields allowed).
std::string ObjectSchema(const std::string& title, const json& properties,
                         const std::vector<std::string>& required) {
  return json{{"$schema", "https://json-schema.org/draft/2020-12/schema"},
              {"title", title},
              {"type", "object"},
              {"properties", properties},
              {"required", required}}
      .dump();
}

json Points3() {
  return {{"type", "array"},
          {"items", {{"type", "array"}, {"items", {{"type", "number"}}}, {"minItems", 3}}}};
}

std::string ShapeSchema(const std::string& title) {
  return ObjectSchema(title,
                      {{"trigger_seq", {{"type", "integer"}}},
                       {"trigger_utime", {{"type", "integer"}}},
                       {"valid", {{"type", "boolean"}}},
                       {"error", {{"type", "string"}}},
                       {"centerline", Points3()},
                       {"markers", Points3()},
                       {"tip", {{"type", "array"}, {"items", {{"type", "number"}}}}},
                       {"q", {{"type", {"array", "null"}}}},
                       {"length", {{"type", "number"}}},
                       {"latency_ms", {{"type", "number"}}},
                       {"stages", {{"type", "array"}}}},
                      {"trigger_seq", "valid", "centerline", "tip"});
}

// foxglove.CompressedImage, as Foxglove's own JSON Schema has it.
std::string CompressedImageSchema() {
  return ObjectSchema(
      "foxglove.CompressedImage",
      {{"timestamp",
        {{"type", "object"},
         {"properties", {{"sec", {{"type", "integer"}}}, {"nsec", {{"type", "integer"}}}}}}},
       {"frame_id", {{"type", "string"}}},
       {"data", {{"type", "string"}, {"contentEncoding", "base64"}}},
       {"format", {{"type", "string"}}}},
      {"timestamp", "frame_id", "data", "format"});
}

std::vector<FoxgloveChannel> FoxgloveChannels(const std::vector<Camera>& cameras) {
  const std::string prefix = kFoxglovePrefix;
  std::vector<FoxgloveChannel> list = {
      {prefix + "shape", "/shapesense/shape", "shapesense.Shape", ShapeSchema("shapesense.Shape")},
      {prefix + "truth", "/shapesense/truth", "shapesense.Shape", ShapeSchema("shapesense.Shape")},
      {prefix + "health", "/shapesense/health", "shapesense.Health",
       ObjectSchema("shapesense.Health",
                    {{"now_utime", {{"type", "integer"}}}, {"rows", {{"type", "array"}}}},
                    {"rows"})},
      {prefix + "stats", "/shapesense/stats", "shapesense.Stats",
       ObjectSchema("shapesense.Stats",
                    {{"frame_set_rate_hz", {{"type", "number"}}},
                     {"lost_sets", {{"type", "integer"}}},
                     {"latency_ms", {{"type", "object"}}}},
                    {"frame_set_rate_hz", "lost_sets"})},
      {prefix + "controller", "/shapesense/controller", "shapesense.Controller",
       ObjectSchema("shapesense.Controller",
                    {{"mode", {{"type", "string"}}},
                     {"gate", {{"type", "string"}}},
                     {"commanded_mm", {{"type", "array"}}},
                     {"actual_mm", {{"type", "array"}}}},
                    {"mode", "gate"})},
      {prefix + "target", "/shapesense/target", "shapesense.Target",
       ObjectSchema("shapesense.Target",
                    {{"kind", {{"type", "string"}}}, {"q", {{"type", "array"}}}}, {"kind"})}};
  for (const Camera& camera : cameras) {
    list.push_back({prefix + "camera/" + camera.name, "/camera/" + camera.name + "/compressed",
                    "foxglove.CompressedImage", CompressedImageSchema()});
  }
  return list;
}

// A browser's message: only an e-stop with the right token does anything.
// (On the web server's thread: LCM's publish is thread-safe.)
std::string OnBrowserMessage(const std::string& text, const std::string& token, LcmBus& bus,
                             ServiceStatus& status) {
  const json request = json::parse(text, nullptr, false);
  if (!request.is_object() || request.value("type", "") != "estop") return "";
  const auto reply = [](bool ok, const std::string& message) {
    return json{{"type", "estop_result"}, {"ok", ok}, {"message", message}}.dump();
  };
  if (token.empty()) return reply(false, "this monitor has no e-stop (no token configured)");
  const json given = request.value("token", json());
  if (!given.is_string() || !TokenMatches(token, given.get<std::string>())) {
    status.Rejected();
    status.Note("e-stop request with a wrong token refused");
    return reply(false, "wrong token: nothing sent");
  }
  estop_t estop{};
  estop.engaged = true;
  estop.reason = "operator pressed the web monitor's e-stop";
  estop.source = "shapesense-monitor on " + HostName();
  if (!bus.Publish(channels::kEstop, estop)) return reply(false, "publishing the e-stop failed");
  status.Note("e-stop engaged from the web page");
  return reply(true, "e-stop engaged (latched until a release)");
}

}  // namespace

std::string ReadEstopToken(const fs::path& file) {
  struct stat info {};
  if (stat(file.c_str(), &info) != 0) throw InputError(file.string() + ": cannot be read");
  if ((info.st_mode & 077) != 0) {
    throw InputError(file.string() + ": readable by others (chmod 600 it)");
  }
  std::string token = ReadTextFile(file);
  while (!token.empty() && (token.back() == '\n' || token.back() == '\r')) token.pop_back();
  if (token.size() < kMinTokenLength || token.find('\n') != std::string::npos) {
    throw InputError(file.string() + ": expected one line of at least " +
                     std::to_string(kMinTokenLength) + " characters (the e-stop token)");
  }
  return token;
}

bool TokenMatches(const std::string& expected, const std::string& given) {
  return expected.size() == given.size() &&
         CRYPTO_memcmp(expected.data(), given.data(), expected.size()) == 0;
}

service_status_t RunMonitor(const MonitorArgs& args, const std::atomic<bool>& stop,
                            std::ostream& log) {
  const MonitorSetup setup = LoadSetup(args);
  LcmBusOptions bus_options = LcmBusOptions::FromEnvironment(args.lcm_url.value_or(""));
  bus_options.auth.read_only = true;
  LcmBus bus(bus_options);
  ServiceStatus status("monitor");
  MonitorModelOptions model_options;
  model_options.host = HostName();
  model_options.rig_prefix = bus_options.prefix;
  model_options.estop_enabled = !setup.token.empty();
  model_options.started_utime = NowUtime();
  MonitorModel model(model_options, setup.cameras, setup.rig, setup.geometry);
  std::string hello = HelloJson(model_options, setup.cameras);

  WebServerOptions web_options;
  web_options.listen = args.http;
  web_options.listen_fd = TakeListeningSocket();
  web_options.foxglove = FoxgloveChannels(setup.cameras);
  web_options.folders["/"] = args.assets.empty() ? DefaultAssets() : args.assets;
  if (!fs::is_regular_file(web_options.folders["/"] / "index.html")) {
    throw InputError("the monitor's page is not in " + web_options.folders["/"].string() +
                     " (no index.html; --assets)");
  }
  WebServer web(
      web_options, [&hello] { return hello; },
      [&](const std::string& text) { return OnBrowserMessage(text, setup.token, bus, status); });
  MonitorService service(model, web, status);
  service.Subscribe(bus);
  log << "shapesense-monitor: serving http://" << web.address() << "/ "
      << (setup.token.empty() ? "(read-only)" : "(with an e-stop button)") << std::endl;
  SystemdNotifier supervisor;
  supervisor.Ready("serving http://" + web.address() + "/");
  RunBusLoop(
      bus, stop, args.duration_s, [&](int64_t now) { service.Poll(bus, now); }, supervisor);
  return status.Snapshot(NowUtime(), bus.Rejected());
}

}  // namespace shapesense
