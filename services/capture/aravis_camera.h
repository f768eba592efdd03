#pragma once

// The Aravis backend: GigE Vision and USB3 Vision cameras through Aravis 0.8.
//
// Open() finds the device by Aravis device id, serial number or IP address,
// sets pixel format, size, exposure, gain, trigger (free run at frame_rate,
// software, or hardware on trigger_line), GigE packet size and socket buffer,
// and starts a stream of buffer_count buffers. Grab() delivers only complete
// buffers, converted to BGR (Bayer debayered, RGB8 swapped) or mono;
// incomplete or corrupted ones are dropped and counted. Each frame carries
// the frame-set of the software trigger it answers, proven by its exposure
// timestamp (PTP time) against the trigger's window (exposure_matcher.h);
// a frame nothing proves is dropped and counted with its reason. A lost device (heartbeat lost, a
// failed trigger, or a device that stops answering while no frames come) makes Grab() throw
// CameraError; Close() then Open() reconnects once it is back. Every error names the camera and the
// device.
//
// Open() and a Trigger() to a device that vanished block for Aravis's GVCP
// timeout (5 tries of 500 ms in 0.8), and so does Close() of one that
// vanished unnoticed (a lost one is released in the background), so a
// service serving several cameras should reconnect each in its own thread.
// Trigger() and Grab() may be called from different threads.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "services/capture/camera_backend.h"

namespace shapesense {

// The backend the capture service creates for `backend: aravis`. Does not
// touch the device until Open().
std::unique_ptr<CameraBackend> MakeAravisCamera(const CameraConfig& config);

// An image buffer in a GenICam pixel format (PFNC code, as ArvPixelFormat)
// as OpenCV BGR (CV_8UC3) or mono (CV_8UC1, for Mono8). Supports Mono8,
// RGB8, BGR8 and the four 8-bit Bayer patterns. An empty Mat when the format
// is not supported or `size` is too small for the image.
cv::Mat DecodeAravisImage(uint32_t pixel_format, const void* data, size_t size, int width,
                          int height);

// The PFNC code of a pixel format name ("Mono8", "RGB8", "BGR8", "BayerRG8",
// "BayerGR8", "BayerGB8", "BayerBG8"); 0 when not one of these.
uint32_t AravisPixelFormatCode(const std::string& name);

}  // namespace shapesense
