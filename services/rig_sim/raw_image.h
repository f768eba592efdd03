#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>

namespace shapesense {

// Writes a BGR image into a camera buffer of width x height pixels in a
// GenICam pixel format (PFNC code): Mono8, Mono16 (little endian), RGB8,
// BGR8, or an 8-bit Bayer mosaic (RG, GR, GB, BG: the colour of each site
// sampled). An image of another size is resized to the buffer first.
// Returns false, writing nothing, for other formats or a buffer smaller than
// width x height x bytes per pixel.
bool EncodeRawImage(const cv::Mat& bgr, uint32_t pixel_format, int width, int height, uint8_t* out,
                    size_t out_size);

// Bytes per pixel of the formats EncodeRawImage writes; 0 for others.
int RawBytesPerPixel(uint32_t pixel_format);

}  // namespace shapesense
