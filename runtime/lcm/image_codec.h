#pragma once

// image_t and the images of OpenCV, both ways.
// Every message from the network is checked field by field before use: a
// malformed one yields a reason ("cam0: size: expected 921600 bytes
// (row_stride 1920 x height 480), got 1000"), never a crash. Messages built
// here from the libraries' types are always valid.
#include <cstdint>
#include <opencv2/core.hpp>
#include <span>
#include <string>

#include "shapesense/image_t.hpp"

namespace shapesense {

// Largest image side accepted, px (the carver's limit).
inline constexpr int kMaxImageSide = 32767;

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
// The same for an image whose bytes lie elsewhere (DecodeImageFields):
// `bytes` stands for image.data.
std::string ValidateImageMessage(const image_t& image, std::span<const uint8_t> bytes);

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
// The same with the image's bytes elsewhere: with kViewWhenPossible, `bgr`
// may view `bytes`.
std::string ImageMessageToBgr(const image_t& image, std::span<const uint8_t> bytes, cv::Mat* bgr,
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

}  // namespace shapesense
