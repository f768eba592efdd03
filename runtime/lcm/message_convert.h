#pragma once

// Conversions between the LCM messages and the libraries' types. Every
// message from the network is checked field by field before use: a malformed
// one yields a reason ("cam0: size: expected 921600 bytes (row_stride 1920 x
// height 480), got 1000"), never a crash. Messages built here from the
// libraries' types are always valid.
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "libs/carving/voxel_grid.h"
#include "libs/centerline/shape_estimator.h"
#include "libs/mechanics/configuration.h"
#include "shapesense/image_t.hpp"
#include "shapesense/shape_t.hpp"
#include "shapesense/stage_time_t.hpp"
#include "shapesense/voxel_cloud_t.hpp"

namespace shapesense {

// Largest image side accepted, px (the carver's limit).
inline constexpr int kMaxImageSide = 32767;

// ---- image_t ---------------------------------------------------------------
//
// Raw images hold rows of row_stride bytes (at least width × bytes per pixel).
// Compressed images (PNG, JPEG) hold the encoded pixels in the layout of
// pixel_format: one channel for MONO8 and the Bayer mosaics, three for BGR8
// and RGB8 (in that order); YUYV cannot be compressed, JPEG only holds
// MONO8, BGR8 and RGB8 (a lossy mosaic would not demosaic), and row_stride
// is 0. An MJPEG camera's frames can be sent as they come: JPEG, BGR8.

// Bytes per pixel of a raw image in `pixel_format`; 0 for an unknown format.
int BytesPerPixel(int8_t pixel_format);
// "MONO8", "BGR8", ..., or "unknown (N)".
std::string PixelFormatName(int8_t pixel_format);

// Checks every field without decoding the pixels (cheap enough for an LCM
// callback): camera name, size, format, compression and its signature,
// stride, byte count, times, stage times. "" when usable, else the reason.
std::string ValidateImageMessage(const image_t& image);

// Decodes to 8-bit BGR: BGR8 as is, RGB8 swapped, MONO8 replicated, Bayer
// demosaiced (bilinear), YUYV converted, PNG/JPEG decoded first. "" on
// success, else the reason (a message that fails ValidateImageMessage, or
// compressed data that does not decode to width × height).
enum class ImageCopy {
  kAlways,
  // A raw BGR8 image becomes a view of the message's bytes (no copy): the
  // message must outlive `bgr` and stay unchanged.
  kViewWhenPossible,
};
// `bgr` keeps its buffer when it owns one of the right size; a view (of an
// earlier message) is never written into.
std::string ImageMessageToBgr(const image_t& image, cv::Mat* bgr,
                              ImageCopy copy = ImageCopy::kAlways);
// Decodes to 8-bit grey (colour images converted, MONO8 as is).
std::string ImageMessageToMono(const image_t& image, cv::Mat* mono);

// An image message of `pixels` laid out as `pixel_format` says: CV_8UC1 for
// MONO8 and Bayer mosaics, CV_8UC3 BGR for BGR8, CV_8UC3 in R, G, B order for
// RGB8, CV_8UC2 for YUYV. Raw rows are packed (row_stride = width × bytes
// per pixel). Camera, times and stage times are the caller's to fill. Throws
// std::invalid_argument on a type that does not fit the format or an
// unsupported compression of it (a caller's bug, not network input).
image_t ImageToMessage(const cv::Mat& pixels, int8_t pixel_format,
                       int8_t compression = image_t::COMPRESSION_NONE, int jpeg_quality = 95,
                       int png_level = 1);

// The Bayer mosaic a sensor with `bayer_format` (image_t::PIXEL_BAYER_*, named
// by the colours of the top-left 2×2 cell read row by row, as GenICam does)
// would record of a BGR scene: CV_8UC1. For simulation and tests.
cv::Mat MosaicBayer(const cv::Mat& bgr, int8_t bayer_format);

// ---- voxel_cloud_t ---------------------------------------------------------
//
// Labels on the wire: 0 body, k > 0 marker colour class k (the tape is
// class 1); in VoxelCloud: kLabelBody, kLabelMarker.

// Grid, voxels and labels; header, trigger and stage times are the caller's.
voxel_cloud_t VoxelCloudToMessage(const VoxelCloud& cloud);
// Checks dims (positive, at most 2^31 voxels), origin and voxel size
// (finite, positive), counts, and that the indices are in the grid without
// repeats. "" or the reason.
std::string ValidateVoxelCloudMessage(const voxel_cloud_t& message);
// Validates, then fills `cloud` with the voxels in ascending order.
std::string VoxelCloudFromMessage(const voxel_cloud_t& message, VoxelCloud* cloud);

// ---- shape_t ---------------------------------------------------------------
//
// shape_t has no field for the tube radius: it does not survive the round trip.

// Everything of the estimate (an invalid one carries only its error);
// header, trigger and stage times are the caller's.
shape_t ShapeToMessage(const ShapeEstimate& shape);
// Checks the counts and that the numbers are finite; "" or the reason.
std::string ValidateShapeMessage(const shape_t& message);
std::string ShapeFromMessage(const shape_t& message, ShapeEstimate* shape);
// Sets has_configuration, q and configuration_residual_mm (the arc fit's RMS
// residual, mm; 0 for a true configuration).
void SetMessageConfiguration(const Configuration& q, double residual_mm, shape_t* message);
// The message's q, when it has one.
std::optional<Configuration> MessageConfiguration(const shape_t& message);

// ---- stage_time_t ----------------------------------------------------------

stage_time_t MakeStageTime(const std::string& stage, int64_t duration_us, int64_t end_utime);
// The stage of that name, or nullptr.
const stage_time_t* FindStageTime(const std::vector<stage_time_t>& stages,
                                  const std::string& stage);
// Adds a stage; when one of that name is there already (the images of a
// frame-set each carry their own "capture"), keeps the later end and the
// longer duration: the frame-set waited for its slowest image.
void MergeStageTime(const stage_time_t& stage, std::vector<stage_time_t>* stages);

}  // namespace shapesense
