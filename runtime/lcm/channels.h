#pragma once

// Every LCM channel of shapesense, in one place. A rig can run several
// pipelines side by side on one LCM network by giving each a prefix
// (e.g. "RIG2_": the rig file's `prefix`, SHAPESENSE_RIG_PREFIX): LcmBus
// adds it to every channel it publishes or subscribes to and takes it off
// the channels its handlers see, so the names here never carry it. Which
// network each channel takes: channel_networks.h.
#include <string>

namespace shapesense::channels {

// Images of one camera: image_t.
inline std::string Image(const std::string& camera) { return "SHAPESENSE_IMAGE_" + camera; }
// Every camera's images: the LCM regular expression the carving service subscribes to.
inline constexpr const char* kImagePattern = "SHAPESENSE_IMAGE_.*";
// Silhouettes for monitoring, at a low rate: image_t (mono, 255 inside).
inline std::string Silhouette(const std::string& camera) {
  return "SHAPESENSE_SILHOUETTE_" + camera;
}
inline constexpr const char* kSilhouettePattern = "SHAPESENSE_SILHOUETTE_.*";
// A camera's preview for people (the web monitor): image_t, a small JPEG,
// a few a second, on the rig network.
inline std::string Preview(const std::string& camera) { return "SHAPESENSE_PREVIEW_" + camera; }
inline constexpr const char* kPreviewPattern = "SHAPESENSE_PREVIEW_.*";
// The silhouettes of each frame-set, compact (what the shape service refines
// against): silhouettes_t, one datagram.
inline constexpr const char* kSilhouettes = "SHAPESENSE_SILHOUETTES";
// The visual hull of each frame-set: voxel_cloud_t.
inline constexpr const char* kVoxels = "SHAPESENSE_VOXELS";
// The measured shape: shape_t.
inline constexpr const char* kShape = "SHAPESENSE_SHAPE";
// The virtual rig's ground truth of each frame-set: shape_t.
inline constexpr const char* kTruth = "SHAPESENSE_TRUTH";
// Health of a service, 1 Hz: service_status_t.
inline std::string Status(const std::string& service) { return "SHAPESENSE_STATUS_" + service; }
inline constexpr const char* kStatusPattern = "SHAPESENSE_STATUS_.*";
// Tendon commands and actuator state: tendon_command_t, tendon_state_t.
inline constexpr const char* kTendonCommand = "SHAPESENSE_TENDON_COMMAND";
inline constexpr const char* kTendonState = "SHAPESENSE_TENDON_STATE";
// Targets streamed to the controller: configuration_target_t.
inline constexpr const char* kTarget = "SHAPESENSE_TARGET";
// Emergency stop and its release: estop_t.
inline constexpr const char* kEstop = "SHAPESENSE_ESTOP";
// The link between the controller's rig driver and the virtual rig's tendon
// plant: the commands (tendon_command_t) and the plant's actuators as they
// stand (tendon_state_t). The controller publishes what it commanded and what
// its actuators report on kTendonCommand / kTendonState, whatever the driver.
inline constexpr const char* kPlantCommand = "SHAPESENSE_PLANT_COMMAND";
inline constexpr const char* kPlantState = "SHAPESENSE_PLANT_STATE";

}  // namespace shapesense::channels
