#include "services/monitor/monitor_model.h"

#include <openssl/evp.h>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "libs/control/safety_gate.h"
#include "libs/mechanics/configuration_geometry.h"
#include "runtime/lcm/tendon_message.h"

namespace shapesense {
namespace {

using nlohmann::json;

constexpr double kFrustumDepthMm = 150.0;
constexpr size_t kLatencyWindow = 300;
constexpr int64_t kRateWindowUs = 2'000'000;
constexpr int64_t kControllerPeriodUs = 50'000;  // 20 Hz: more than a person reads
constexpr int64_t kVoxelPeriodUs = 250'000;      // 4 Hz

// Two decimals: what a view needs, and a third of the JSON.
double Rounded(double value) { return std::round(value * 100.0) / 100.0; }

json Point(const Vec3& point) {
  return json::array({Rounded(point.x()), Rounded(point.y()), Rounded(point.z())});
}

json Point(const double (&point)[3]) { return Point(Vec3(point[0], point[1], point[2])); }

json Points(const std::vector<std::vector<double>>& points) {
  json list = json::array();
  for (const std::vector<double>& point : points) {
    if (point.size() == 3) list.push_back(Point(Vec3(point[0], point[1], point[2])));
  }
  return list;
}

json Pixels(const Camera& camera, const std::vector<Vec3>& points) {
  json list = json::array();
  for (const Vec3& point : points) {
    if (const std::optional<Vec2> pixel = camera.Project(point)) {
      list.push_back(json::array({Rounded(pixel->x()), Rounded(pixel->y())}));
    }
  }
  return list;
}

std::vector<Vec3> Vectors(const std::vector<std::vector<double>>& points) {
  std::vector<Vec3> vectors;
  vectors.reserve(points.size());
  for (const std::vector<double>& p : points) {
    if (p.size() == 3) vectors.emplace_back(p[0], p[1], p[2]);
  }
  return vectors;
}

json Runs(const std::vector<int16_t>& rows, const std::vector<int16_t>& begins,
          const std::vector<int16_t>& ends) {
  json runs = json::array();
  const size_t count = std::min({rows.size(), begins.size(), ends.size()});
  for (size_t i = 0; i < count; ++i) runs.push_back(json::array({rows[i], begins[i], ends[i]}));
  return runs;
}

json ShapeJson(const char* type, const shape_t& shape, double latency_ms) {
  json stages = json::array();
  for (const stage_time_t& stage : shape.stage_times) {
    stages.push_back(
        {{"stage", stage.stage}, {"ms", Rounded(static_cast<double>(stage.duration_us) * 1e-3)}});
  }
  json q = nullptr;
  if (shape.has_configuration) q = json::array({shape.q[0], shape.q[1], shape.q[2], shape.q[3]});
  return {{"type", type},
          {"trigger_seq", shape.trigger_seq},
          {"trigger_utime", shape.trigger_utime},
          {"valid", shape.valid != 0},
          {"error", shape.error},
          {"centerline", Points(shape.centerline)},
          {"markers", Points(shape.markers)},
          {"tip", Point(shape.tip)},
          {"q", q},
          {"length", Rounded(shape.length)},
          {"residual_mm", Rounded(shape.centerline_residual_mm)},
          {"stages", stages},
          {"latency_ms", Rounded(latency_ms)}};
}

// The gate in one word: what an operator must know first.
const char* GateState(uint32_t reasons) {
  if ((reasons & kGateEmergencyStop) != 0) return "estop";
  if ((reasons & (kGateSensingLost | kGateStoppedUntilRearmed)) != 0) return "stopped";
  if ((reasons & kGateSensingStale) != 0) return "stale";
  if ((reasons & (kGateAwaitingSensing | kGateInvalidProposal | kGateInvalidPeriod)) != 0) {
    return "held";
  }
  return "ok";
}

json SplitReasons(uint32_t reasons) {
  json list = json::array();
  const std::string text = DescribeGateReasons(reasons);
  size_t start = 0;
  while (start < text.size()) {
    const size_t comma = text.find(", ", start);
    list.push_back(text.substr(start, comma - start));
    if (comma == std::string::npos) break;
    start = comma + 2;
  }
  return list;
}

double Percentile(std::deque<double> values, double fraction) {
  if (values.empty()) return 0.0;
  const size_t index = std::min(values.size() - 1,
                                static_cast<size_t>(fraction * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index),
                   values.end());
  return values[index];
}

// Arrival times of the last kRateWindowUs.
void Remember(std::deque<int64_t>* times, int64_t utime) {
  times->push_back(utime);
  while (utime - times->front() > kRateWindowUs) times->pop_front();
}

// Per second, over the arrivals of the last kRateWindowUs (0 when none lately).
double RateHz(const std::deque<int64_t>& times, int64_t now_utime) {
  if (times.size() < 2 || now_utime - times.back() > kRateWindowUs) return 0.0;
  return static_cast<double>(times.size() - 1) /
         (static_cast<double>(times.back() - times.front()) * 1e-6);
}

// A page update whose JSON Foxglove clients get too.
WebUpdate Text(const std::string& channel, const json& value, int64_t utime) {
  return {channel, value.dump(), false, kFoxglovePrefix + channel, utime};
}

std::string Base64(const std::vector<uint8_t>& bytes) {
  std::string text(4 * ((bytes.size() + 2) / 3) + 1, '\0');
  const int length = EVP_EncodeBlock(reinterpret_cast<unsigned char*>(text.data()), bytes.data(),
                                     static_cast<int>(bytes.size()));
  text.resize(static_cast<size_t>(std::max(length, 0)));
  return text;
}

// foxglove.CompressedImage, JSON-encoded.
WebUpdate FoxgloveImage(const image_t& preview) {
  const int64_t utime = preview.trigger_utime;
  const json image = {
      {"timestamp", {{"sec", utime / 1'000'000}, {"nsec", (utime % 1'000'000) * 1000}}},
      {"frame_id", preview.camera},
      {"format", "jpeg"},
      {"data", Base64(preview.data)}};
  return {kFoxglovePrefix + std::string("camera/") + preview.camera, image.dump(), false, "",
          utime};
}

}  // namespace

std::string HelloJson(const MonitorModelOptions& options, const std::vector<Camera>& cameras) {
  json list = json::array();
  for (const Camera& camera : cameras) {
    json frustum = json::array({Point(camera.Center())});
    const double w = camera.width - 1.0;
    const double h = camera.height - 1.0;
    for (const Vec2& corner : {Vec2(0, 0), Vec2(w, 0), Vec2(w, h), Vec2(0, h)}) {
      const Vec3 direction = camera.RayDirectionWorld(corner);
      const Vec3 axis = camera.cam_from_world.rotation().row(2).transpose();
      frustum.push_back(
          Point(camera.Center() + direction * (kFrustumDepthMm / direction.dot(axis))));
    }
    list.push_back({{"name", camera.name},
                    {"width", camera.width},
                    {"height", camera.height},
                    {"frustum", frustum}});
  }
  return json{{"type", "hello"},
              {"version", 1},
              {"host", options.host},
              {"rig_prefix", options.rig_prefix},
              {"estop_enabled", options.estop_enabled},
              {"started_utime", options.started_utime},
              {"cameras", list}}
      .dump();
}

MonitorModel::MonitorModel(MonitorModelOptions options, std::vector<Camera> cameras,
                           std::optional<RigFile> rig, std::optional<TargetGeometry> geometry)
    : options_(std::move(options)),
      cameras_(std::move(cameras)),
      geometry_(std::move(geometry)),
      board_(std::move(rig), options_.stale_after_s, options_.missing_after_s,
             /*expect_heard=*/true) {}

MonitorModel::FrameSet& MonitorModel::FrameSetOf(int64_t trigger_seq, int64_t trigger_utime) {
  FrameSet& set = frame_sets_[trigger_seq];
  set.trigger_utime = std::max(set.trigger_utime, trigger_utime);
  return set;
}

void MonitorModel::ForgetOldFrameSets() {
  while (frame_sets_.size() > static_cast<size_t>(options_.kept_frame_sets)) {
    frame_sets_.erase(frame_sets_.begin());
  }
}

std::vector<WebUpdate> MonitorModel::OnShape(const shape_t& shape, int64_t receive_utime) {
  Count(shape, receive_utime);
  board_.Observe(shape);
  FrameSetOf(shape.trigger_seq, shape.trigger_utime).shape = shape;
  last_shape_ = shape;
  const double latency_ms = static_cast<double>(receive_utime - shape.trigger_utime) * 1e-3;
  std::vector<WebUpdate> updates = ReleasePictures(shape.trigger_utime);
  updates.push_back(Text("shape", ShapeJson("shape", shape, latency_ms), shape.trigger_utime));
  if (target_) updates.push_back(ControllerUpdate());
  ForgetOldFrameSets();
  return updates;
}

std::vector<WebUpdate> MonitorModel::OnTruth(const shape_t& truth) {
  return {Text("truth", ShapeJson("truth", truth, 0.0), truth.trigger_utime)};
}

std::vector<WebUpdate> MonitorModel::OnSilhouettes(const silhouettes_t& silhouettes,
                                                   int64_t receive_utime) {
  Remember(&stats_.frame_set_receive_utimes, receive_utime);
  FrameSetOf(silhouettes.trigger_seq, silhouettes.trigger_utime).silhouettes = silhouettes;
  ForgetOldFrameSets();
  return {};
}

std::vector<WebUpdate> MonitorModel::OnVoxels(const voxel_cloud_t& cloud) {
  const int64_t since = cloud.trigger_utime - voxels_sent_utime_;
  if (since >= 0 && since < kVoxelPeriodUs) return {};
  voxels_sent_utime_ = cloud.trigger_utime;
  json points = json::array();
  const int64_t nx = cloud.dims[0];
  const int64_t ny = cloud.dims[1];
  for (const int32_t index : cloud.voxels) {
    // The cell's integer coordinates, from i = x + nx * (y + ny * z).
    const int64_t x = index % nx;
    const int64_t y = (index / nx) % ny;
    const int64_t z = index / (nx * ny);
    const Vec3 cell(static_cast<double>(x), static_cast<double>(y), static_cast<double>(z));
    const Vec3 centre = Vec3(cloud.grid_origin[0], cloud.grid_origin[1], cloud.grid_origin[2]) +
                        cell * cloud.voxel_size;
    for (int axis = 0; axis < 3; ++axis) {
      points.push_back(std::round(centre[axis] * 10.0) / 10.0);
    }
  }
  // The page's alone: Foxglove clients get the shapes, not the hull.
  return {{"voxels",
           json{{"type", "voxels"},
                {"trigger_seq", cloud.trigger_seq},
                {"voxel_size", cloud.voxel_size},
                {"points", points}}
               .dump(),
           false, "", cloud.trigger_utime}};
}

std::vector<WebUpdate> MonitorModel::OnPreview(image_t preview) {
  FrameSet& set = FrameSetOf(preview.trigger_seq, preview.trigger_utime);
  const int64_t trigger_utime = preview.trigger_utime;
  set.previews.push_back(std::move(preview));
  std::vector<WebUpdate> updates = ReleasePictures(trigger_utime);
  ForgetOldFrameSets();
  return updates;
}

// A picture goes out once its frame-set's shape is here, or once a later
// frame-set's shape (shapes come in trigger order), or a picture
// `overlay_wait_s` younger, says that it will not come.
std::vector<WebUpdate> MonitorModel::ReleasePictures(int64_t newest_trigger_utime) {
  const int64_t wait_us = static_cast<int64_t>(options_.overlay_wait_s * 1e6);
  const int64_t last_shape_seq = last_shape_ ? last_shape_->trigger_seq : -1;
  std::vector<WebUpdate> updates;
  for (auto& [seq, set] : frame_sets_) {
    if (set.previews.empty()) continue;
    const bool ready = set.shape.has_value() || seq < last_shape_seq ||
                       newest_trigger_utime - set.trigger_utime > wait_us;
    if (!ready) continue;
    for (const image_t& preview : set.previews) {
      updates.push_back(CameraFrame(preview, set));
      updates.push_back(FoxgloveImage(preview));
    }
    set.previews.clear();
  }
  return updates;
}

WebUpdate MonitorModel::CameraFrame(const image_t& preview, const FrameSet& set) {
  const auto camera = std::find_if(cameras_.begin(), cameras_.end(),
                                   [&](const Camera& c) { return c.name == preview.camera; });
  const bool calibrated = camera != cameras_.end();
  // The overlays are in the camera's pixels; the JPEG may be smaller.
  json header = {{"type", "camera"},
                 {"camera", preview.camera},
                 {"trigger_seq", preview.trigger_seq},
                 {"width", calibrated ? camera->width : preview.width},
                 {"height", calibrated ? camera->height : preview.height},
                 {"silhouette", nullptr},
                 {"centerline", nullptr},
                 {"markers", json::array()},
                 {"tip", nullptr}};
  if (set.shape && set.shape->valid && calibrated) {
    header["centerline"] = Pixels(*camera, Vectors(set.shape->centerline));
    header["markers"] = Pixels(*camera, Vectors(set.shape->markers));
    const json tip =
        Pixels(*camera, {Vec3(set.shape->tip[0], set.shape->tip[1], set.shape->tip[2])});
    if (!tip.empty()) header["tip"] = tip[0];
  }
  for (const silhouette_view_t& view :
       set.silhouettes ? set.silhouettes->views : std::vector<silhouette_view_t>{}) {
    if (view.camera != preview.camera) continue;
    header["silhouette"] = {{"mask", Runs(view.mask_row, view.mask_begin, view.mask_end)},
                            {"tape", Runs(view.tape_row, view.tape_begin, view.tape_end)}};
  }
  const std::string text = header.dump();
  std::string payload(4, '\0');
  const auto length = static_cast<uint32_t>(text.size());
  for (int i = 0; i < 4; ++i) payload[i] = static_cast<char>((length >> (8 * i)) & 0xff);
  payload += text;
  payload.append(preview.data.begin(), preview.data.end());
  return {"camera/" + preview.camera, std::move(payload), true, "", preview.trigger_utime};
}

void MonitorModel::Count(const shape_t& shape, int64_t receive_utime) {
  if (stats_.last_trigger_seq >= 0 && shape.trigger_seq > stats_.last_trigger_seq + 1) {
    stats_.lost_sets += shape.trigger_seq - stats_.last_trigger_seq - 1;
  }
  stats_.last_trigger_seq = std::max(stats_.last_trigger_seq, shape.trigger_seq);
  if (!shape.valid) ++stats_.invalid_shapes;
  Remember(&stats_.shape_receive_utimes, receive_utime);
  stats_.latencies_ms.push_back(static_cast<double>(receive_utime - shape.trigger_utime) * 1e-3);
  if (stats_.latencies_ms.size() > kLatencyWindow) stats_.latencies_ms.pop_front();
  stats_.stage_ms.clear();
  for (const stage_time_t& stage : shape.stage_times) {
    stats_.stage_ms[stage.stage] = static_cast<double>(stage.duration_us) * 1e-3;
  }
}

std::vector<WebUpdate> MonitorModel::OnStatus(const service_status_t& status,
                                              int64_t receive_utime) {
  board_.Observe(status, receive_utime);
  return {};
}

std::optional<Vec3> MonitorModel::TargetTip() const {
  if (!target_) return std::nullopt;
  if (target_->kind == configuration_target_t::KIND_TIP) {
    return Vec3(target_->tip[0], target_->tip[1], target_->tip[2]);
  }
  if (!geometry_) return std::nullopt;
  const Configuration q(target_->q[0], target_->q[1], target_->q[2], target_->q[3]);
  const Polyline line = CenterlineFromConfiguration(q, geometry_->rest, 2.0);
  return geometry_->world_from_base * line.back();
}

std::vector<WebUpdate> MonitorModel::OnTarget(const configuration_target_t& target) {
  target_ = target;
  json centerline = nullptr;
  if (target.kind == configuration_target_t::KIND_CONFIGURATION && geometry_) {
    const Configuration q(target.q[0], target.q[1], target.q[2], target.q[3]);
    centerline = json::array();
    for (const Vec3& point : CenterlineFromConfiguration(q, geometry_->rest, 2.0)) {
      centerline.push_back(Point(geometry_->world_from_base * point));
    }
  }
  const std::optional<Vec3> tip = TargetTip();
  const bool is_tip = target.kind == configuration_target_t::KIND_TIP;
  return {Text("target",
               {{"type", "target"},
                {"kind", is_tip ? "tip" : "configuration"},
                {"q", json::array({target.q[0], target.q[1], target.q[2], target.q[3]})},
                {"tip", tip ? Point(*tip) : json(nullptr)},
                {"centerline", centerline},
                {"duration_s", target.duration_s},
                {"source", target.source},
                {"utime", target.header.utime}},
               target.header.utime),
          ControllerUpdate()};
}

// The controller's loop publishes at its own rate (100 Hz): at most one
// update per kControllerPeriodUs, except when its mode or gate changes, and
// Tick sends the latest.
std::vector<WebUpdate> MonitorModel::OnTendonCommand(const tendon_command_t& command) {
  const bool changed =
      !command_ || command_->mode != command.mode || command_->gate_reasons != command.gate_reasons;
  command_ = command;
  return ControllerIfDue(command.header.utime, changed);
}

std::vector<WebUpdate> MonitorModel::ControllerIfDue(int64_t utime, bool changed) {
  if (!changed && utime - controller_sent_utime_ < kControllerPeriodUs &&
      utime >= controller_sent_utime_) {
    return {};
  }
  controller_sent_utime_ = utime;
  return {ControllerUpdate()};
}

std::vector<WebUpdate> MonitorModel::OnTendonState(const tendon_state_t& state) {
  state_ = state;
  return ControllerIfDue(state.header.utime, false);
}

std::vector<WebUpdate> MonitorModel::OnEstop(const estop_t& estop) {
  estop_ = estop;
  return {ControllerUpdate()};
}

WebUpdate MonitorModel::ControllerUpdate() const {
  const int64_t utime = command_ ? command_->header.utime : 0;
  return {"controller", ControllerJson(), false, kFoxglovePrefix + std::string("controller"),
          utime};
}

std::string MonitorModel::ControllerJson() const {
  json tip_error = nullptr;
  const std::optional<Vec3> tip = TargetTip();
  if (tip && last_shape_ && last_shape_->valid) {
    const Vec3 sensed(last_shape_->tip[0], last_shape_->tip[1], last_shape_->tip[2]);
    tip_error = Rounded((sensed - *tip).norm());
  }
  const uint32_t reasons = command_ ? static_cast<uint32_t>(command_->gate_reasons) : 0;
  json value = {{"type", "controller"},
                {"utime", command_ ? command_->header.utime : 0},
                {"mode", command_ ? CommandModeName(command_->mode) : "none"},
                {"gate", command_ ? GateState(reasons) : "none"},
                {"gate_reasons", SplitReasons(reasons)},
                {"commanded_mm", command_ ? command_->displacement_mm : std::vector<double>{}},
                {"actual_mm", state_ ? state_->displacement_mm : std::vector<double>{}},
                {"tensions_n", state_ ? state_->tension_n : std::vector<double>{}},
                {"tip_error_mm", tip_error},
                {"estop", estop_ ? json{{"engaged", estop_->engaged != 0},
                                        {"reason", estop_->reason},
                                        {"source", estop_->source}}
                                 : json(nullptr)}};
  return value.dump();
}

std::vector<WebUpdate> MonitorModel::Tick(int64_t now_utime) {
  json health = json::parse(board_.Json(now_utime));
  std::vector<WebUpdate> updates;
  if (command_ || state_) updates.push_back(ControllerUpdate());
  updates.push_back(
      Text("health", {{"type", "health"}, {"now_utime", now_utime}, {"rows", health["programs"]}},
           now_utime));
  json latency = json::object();
  for (const auto& [stage, ms] : stats_.stage_ms) latency[stage] = Rounded(ms);
  if (!stats_.latencies_ms.empty()) latency["total"] = Rounded(stats_.latencies_ms.back());
  updates.push_back(
      Text("stats",
           {{"type", "stats"},
            {"utime", now_utime},
            {"frame_set_rate_hz", Rounded(RateHz(stats_.frame_set_receive_utimes, now_utime))},
            {"shape_rate_hz", Rounded(RateHz(stats_.shape_receive_utimes, now_utime))},
            {"lost_sets", stats_.lost_sets},
            {"invalid_shapes", stats_.invalid_shapes},
            {"latency_ms", latency},
            {"p99_latency_ms", Rounded(Percentile(stats_.latencies_ms, 0.99))}},
           now_utime));
  return updates;
}

}  // namespace shapesense
