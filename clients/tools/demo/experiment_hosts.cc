#include "clients/tools/demo/experiment_hosts.h"

#include <csignal>
#include <lcm/lcm-cpp.hpp>

#include "clients/tools/demo/demo_session.h"
#include "libs/config/options_yaml.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/lcm/channels.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/rig/rig_check.h"
#include "services/controller/controller_config.h"
#include "shapesense/shape_t.hpp"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

// The virtual rig's plant link crosses the bridge only because the plant is
// simulated on the camera host; a real rig's actuators hang off the control
// host. It outlasts the control link's 2 s fault, as a local CAN bus would.
constexpr double kPlantLinkTimeoutS = 4.0;
// lcm-logger on the operator host keeps this many earlier files (--rotate).
constexpr int kLogRotation = 10;

// The logger's files, oldest first (pipeline.lcm.N ... .0), or the one log.
std::vector<fs::path> LogFiles(const fs::path& log) {
  std::vector<fs::path> files;
  for (int i = kLogRotation; i >= 0; --i) {
    const fs::path rotated = log.string() + "." + std::to_string(i);
    if (fs::exists(rotated)) files.push_back(rotated);
  }
  if (files.empty() && fs::exists(log)) files.push_back(log);
  return files;
}

// The frame-set truths in the logger's files: when each was logged (µs,
// the operator's clock) and its trigger sequence number.
std::vector<std::pair<int64_t, int64_t>> LoggedTruths(const std::vector<fs::path>& files) {
  std::vector<std::pair<int64_t, int64_t>> logged;
  for (const fs::path& file : files) {
    lcm::LogFile log(file.string(), "r");
    if (!log.good()) continue;
    while (const lcm::LogEvent* event = log.readNextEvent()) {
      if (event->channel != channels::kTruth) continue;
      shape_t truth;
      if (truth.decode(event->data, 0, static_cast<int>(event->datalen)) < 0) continue;
      logged.emplace_back(event->timestamp, truth.trigger_seq);
    }
  }
  return logged;
}

nlohmann::json FaultToJson(const FaultOutcome& fault) {
  const ControllerConduct& c = fault.conduct;
  nlohmann::json json = {
      {"kind", FaultName(fault.event.fault.kind)},
      {"target", fault.event.fault.target},
      {"at_s", fault.at_s},
      {"lasted_s", static_cast<double>(fault.event.end_utime - fault.event.start_utime) * 1e-6},
      {"controller",
       {{"steps", c.steps},
        {"held_steps", c.held_steps},
        {"stopped_steps", c.stopped_steps},
        {"commands_sent_on_stale_sensing", c.sent_on_stale},
        {"max_sensing_age_s", c.max_sensing_age_s},
        {"first_hold_after_s", c.first_hold_after_s},
        {"first_stop_after_s", c.first_stop_after_s},
        {"resumed_after_s", c.resumed_after_s}}}};
  if (fault.event.fault.kind == FaultKind::kKillShape) {
    json["restarts"] = fault.restarts;
    json["sensing_outage_s"] = fault.sensing_outage_s;
  }
  if (fault.event.fault.kind == FaultKind::kRestartLogger) {
    json["log"] = {{"truth_messages", fault.log.messages},
                   {"missing_while_logging", fault.log.missing_within_runs},
                   {"gap_frame_sets", fault.log.gap_between_runs}};
  }
  return json;
}

}  // namespace

HostLayout::HostLayout(const ExperimentArgs& args, const fs::path& setup_dir,
                       const std::vector<std::string>& cameras, const AuthOptions& auth)
    : hosts_(args.hosts) {
  if (hosts_ == nullptr) return;
  rig_file_ = setup_dir / "rig_hosts.yaml";
  const std::string text = DemoRigFileText(cameras, kDemoLcmUrl, auth);
  WriteFileAtomically(rig_file_, text);
  rig_ = ParseRigFile(text, rig_file_);
  std::string problems;
  for (const std::string& problem : CheckRig(rig_)) problems += "\n  " + problem;
  if (!problems.empty()) throw InputError(rig_file_.string() + ":" + problems);
}

ProgramSpec HostLayout::RigStatus(const fs::path& shapesense) const {
  ProgramSpec spec{
      "rig-status",
      {shapesense.string(), "rig", "status", "--rig", rig_file_.string(), "--once", "--json"},
      "",
      "",
      true};
  Place(&spec);
  return spec;
}

nlohmann::json LastJson(const fs::path& log) {
  const std::string text = fs::exists(log) ? ReadTextFile(log) : "";
  size_t start = text.rfind("\n{\n");
  start = start == std::string::npos ? (text.starts_with("{") ? 0 : text.size()) : start + 1;
  if (start >= text.size()) return nullptr;
  nlohmann::json json = nlohmann::json::parse(text.substr(start), nullptr, false);
  return json.is_discarded() ? nullptr : json;
}

fs::path ControllerConfigForHosts(const fs::path& controller_config, const fs::path& dir) {
  fs::create_directories(dir);
  for (const fs::directory_entry& entry : fs::directory_iterator(controller_config.parent_path())) {
    if (!entry.is_regular_file()) continue;
    fs::copy_file(entry.path(), dir / entry.path().filename(),
                  fs::copy_options::overwrite_existing);
  }
  fs::path client = dir / controller_config.filename();
  const auto client_options =
      OptionsFromYamlText<ControllerClientOptions>(ReadTextFile(client), client.string());
  const fs::path actuators = dir / client_options.actuators;
  auto options = OptionsFromYamlText<ActuatorOptions>(ReadTextFile(actuators), actuators.string());
  options.rig.state_timeout_s = kPlantLinkTimeoutS;
  WriteFileAtomically(actuators,
                      "# Written by `shapesense demo --hosts 3`: config/actuators.yaml with the "
                      "plant link's\n# timeout past the control link's 2 s fault.\n" +
                          OptionsToDocumentedYaml(options));
  return client;
}

void RotateLogs(DemoPlan& plan) {
  for (ProgramSpec& process : plan.pipeline) {
    if (process.name != "lcm-logger") continue;
    for (std::string& arg : process.argv) {
      if (arg == "--force") arg = "--rotate=" + std::to_string(kLogRotation);
    }
  }
  for (int i = 0; i <= kLogRotation; ++i) {
    fs::remove(plan.log.string() + "." + std::to_string(i));
  }
}

void JudgeLogs(const fs::path& log, RigNetworkReport& rig) {
  std::vector<int64_t> restarts;
  for (const FaultOutcome& fault : rig.faults) {
    if (fault.event.fault.kind == FaultKind::kRestartLogger) {
      restarts.push_back(fault.event.end_utime);
    }
  }
  if (restarts.empty()) return;
  const LogContinuity continuity = JudgeContinuity(SplitAt(LoggedTruths(LogFiles(log)), restarts));
  for (FaultOutcome& fault : rig.faults) {
    if (fault.event.fault.kind == FaultKind::kRestartLogger) fault.log = continuity;
  }
}

FaultInjector MakeFaultInjector(const ExperimentArgs& args, const DemoPlan& plan,
                                ProcessGroup& processes) {
  const VirtualHosts* hosts = args.hosts;
  ProgramSpec logger;
  for (const ProgramSpec& process : plan.pipeline) {
    if (process.name == "lcm-logger") logger = process;
  }
  return FaultInjector(args.faults, {[hosts](bool up) { hosts->SetLink(kControlHostName, up); },
                                     [&processes] { processes.Signal("shape", SIGKILL); },
                                     [&processes, logger] {
                                       processes.Stop(logger.name);
                                       const int64_t between = NowUtime();
                                       processes.Start(logger, kDemoStartTimeout);
                                       return between;
                                     }});
}

void JudgeFaults(const FaultInjector& injector, const FaultEvidence& evidence,
                 RigNetworkReport& rig) {
  const std::vector<ControllerStep> steps =
      ParseControllerSteps(ReadTextFile(evidence.steps_csv), evidence.steps_csv.string());
  const std::vector<FaultEvent>& events = injector.events();
  for (size_t i = 0; i < events.size(); ++i) {
    FaultOutcome outcome;
    outcome.event = events[i];
    outcome.at_s = static_cast<double>(events[i].start_utime - evidence.origin_utime) * 1e-6;
    const int64_t until = i + 1 < events.size() ? events[i + 1].start_utime : evidence.end_utime;
    outcome.conduct = JudgeConduct(steps, events[i], until, evidence.hold_age_s);
    // The shapes as the operator heard them: an outage of the shape service
    // only (a pulled control link is the controller's, seen in its steps).
    if (events[i].fault.kind == FaultKind::kKillShape) {
      outcome.sensing_outage_s = OutageAround(evidence.shape_times, events[i].start_utime);
      outcome.restarts = evidence.shape_restarts;
    }
    rig.faults.push_back(outcome);
  }
}

std::map<std::string, std::map<std::string, double>> MeasuredClockOffsetsMs(
    const std::map<std::string, service_status_t>& status_by_host) {
  std::map<std::string, std::map<std::string, double>> offsets;
  for (const auto& [host, status] : status_by_host) {
    for (size_t i = 0; i < status.clock_offset_hosts.size(); ++i) {
      offsets[host][status.clock_offset_hosts[i]] =
          static_cast<double>(status.clock_offsets_us[i]) * 1e-3;
    }
  }
  return offsets;
}

RigNetworkReport DescribeHosts(const VirtualHosts& hosts, const DemoPlan& plan,
                               const std::vector<std::string>& modes) {
  RigNetworkReport rig;
  rig.hosts = hosts.hosts();
  for (const VirtualHostSpec& host : rig.hosts) rig.addresses[host.name] = hosts.Address(host.name);
  for (const ProgramSpec& process : plan.pipeline) {
    rig.programs[DemoHostOf(process.name)].push_back(process.name);
  }
  for (const std::string& mode : modes)
    rig.programs[kControlHostName].push_back("controller-" + mode);
  rig.programs[kOperatorHostName].push_back("rig-status");
  return rig;
}

RigNetworkWatch::RigNetworkWatch(const HostLayout& layout)
    : layout_(layout),
      census_(layout.active() ? std::make_unique<NetworkCensus>(kDemoRigNetworkUrl) : nullptr) {}

void RigNetworkWatch::Begin() {
  if (!layout_.active()) return;
  begin_ = layout_.hosts().Bytes(kControlHostName);
  begin_utime_ = NowUtime();
}

void RigNetworkWatch::End(RigNetworkReport& rig) const {
  const VirtualHosts::LinkBytes end = layout_.hosts().Bytes(kControlHostName);
  const double seconds = static_cast<double>(NowUtime() - begin_utime_) * 1e-6;
  rig.received_bytes_per_s = static_cast<double>(end.received - begin_.received) / seconds;
  rig.sent_bytes_per_s = static_cast<double>(end.sent - begin_.sent) / seconds;
  rig.channel_messages = census_->Counts();
  const std::string images = channels::Image("");  // the channels' common start
  for (const auto& [channel, count] : rig.channel_messages) {
    if (channel.starts_with(images)) rig.image_messages += count;
  }
}

void AddRigToJson(const RigNetworkReport& rig, nlohmann::json& json) {
  nlohmann::json hosts = nlohmann::json::array();
  for (const VirtualHostSpec& host : rig.hosts) {
    const auto programs = rig.programs.find(host.name);
    hosts.push_back({{"name", host.name},
                     {"address", rig.addresses.at(host.name)},
                     {"clock_offset_ms", host.clock_offset_ms},
                     {"programs", programs == rig.programs.end() ? std::vector<std::string>{}
                                                                 : programs->second}});
  }
  json["hosts"] = hosts;
  json["rig_network_bytes_per_s"] = rig.received_bytes_per_s;
  json["rig_network_sent_bytes_per_s"] = rig.sent_bytes_per_s;
  json["image_messages_on_rig_network"] = rig.image_messages;
  json["rig_network_messages"] = rig.channel_messages;
  json["clock_offsets_ms"] = rig.clock_offsets_ms;
  json["faults"] = nlohmann::json::array();
  for (const FaultOutcome& fault : rig.faults) json["faults"].push_back(FaultToJson(fault));
  json["operator_releases"] = rig.releases;
  json["rig_status"] = rig.rig_status;
  json["rig_status_end"] = rig.rig_status_end;
}

}  // namespace shapesense
