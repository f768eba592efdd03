#include "services/capture/capture_options.h"

#include <set>
#include <sstream>
#include <stdexcept>

#include "libs/core/error.h"
#include "runtime/config_file.h"

namespace shapesense {
namespace {

std::string ValidateCameras(const std::vector<CameraConfig>& cameras, const std::string& rig) {
  std::set<std::string> names;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const std::string key = "cameras[" + std::to_string(i) + "].";
    if (const std::string error = cameras[i].Validate(); !error.empty()) return key + error;
    if (!names.insert(cameras[i].name).second) {
      return Expected(key + "name", "a name no other camera has",
                      "'" + cameras[i].name + "' again");
    }
    if (cameras[i].backend == "simulated" && !cameras[i].device.empty() &&
        cameras[i].device != rig) {
      return Expected(key + "device", "empty for a simulated camera (the rig comes from `rig`)",
                      "'" + cameras[i].device + "'");
    }
  }
  return "";
}

void MergeCamera(const CameraConfig& given, std::vector<CameraConfig>& cameras) {
  for (CameraConfig& camera : cameras) {
    if (camera.name != given.name) continue;
    if (camera.backend != given.backend) camera.pixel_format = given.pixel_format;
    camera.backend = given.backend;
    camera.device = given.device;
    return;
  }
  cameras.push_back(given);
}

}  // namespace

std::string BackgroundOptions::Validate() const {
  if (frames < 1 || frames > 1000) return Expected("frames", "1-1000 frames", frames);
  if (out.empty()) return Expected("out", "a folder", "''");
  return "";
}

std::string CaptureServiceOptions::Validate() const {
  if (std::string error = ValidateCameras(cameras, rig); !error.empty()) return error;
  if (!(trigger_rate_hz >= 0.1 && trigger_rate_hz <= 1000.0)) {
    return Expected("trigger_rate_hz", "0.1-1000 Hz", trigger_rate_hz);
  }
  if (compression != "none" && compression != "png") {
    return Expected("compression", "none or png", "'" + compression + "'");
  }
  if (png_level < 0 || png_level > 9) return Expected("png_level", "0-9", png_level);
  if (!(reconnect_interval_s >= 0.05 && reconnect_interval_s <= 60.0)) {
    return Expected("reconnect_interval_s", "0.05-60 s", reconnect_interval_s);
  }
  if (const std::string error = simulation.Validate(); !error.empty()) return "simulation." + error;
  if (const std::string error = background.Validate(); !error.empty()) return "background." + error;
  if (const std::string error = preview.Validate(); !error.empty()) return "preview." + error;
  return "";
}

CaptureServiceOptions LoadCaptureOptions(const std::string& config_path,
                                         const std::vector<std::string>& camera_specs,
                                         std::optional<double> rate_hz) {
  CaptureServiceOptions options = LoadOptionsFile<CaptureServiceOptions>(config_path);
  for (const std::string& spec : camera_specs) {
    try {
      MergeCamera(ParseCameraSpec(spec), options.cameras);
    } catch (const std::invalid_argument& e) {
      throw InputError(e.what());
    }
  }
  if (rate_hz) options.trigger_rate_hz = *rate_hz;
  const std::string source =
      config_path.empty() ? "command line" : config_path + " and command line";
  if (const std::string error = options.Validate(); !error.empty())
    throw InputError(source + ": " + error);
  if (options.cameras.empty()) {
    throw InputError(source +
                     ": cameras: expected at least one camera (in the config file or "
                     "--camera NAME=BACKEND:DEVICE), got none");
  }
  return options;
}

}  // namespace shapesense
