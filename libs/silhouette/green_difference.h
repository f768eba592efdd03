#pragma once

#include <cstdint>

namespace shapesense {

// One row of the first pass over an image, the only pass that reads every
// pixel: writes |green - green_background| and sets, in `over_threshold`
// (one bit per pixel, as a BitMask row), the pixels whose difference exceeds
// `threshold`. `image` and `background` are 8-bit BGR rows of `width` pixels.
// Returns whether any pixel of the row exceeds the threshold.
bool GreenDifferenceRow(const uint8_t* image, const uint8_t* background, int width, int threshold,
                        uint8_t* difference, uint64_t* over_threshold);

// The same without the run-time choice of AVX2 where the CPU has it: OpenCV's
// baseline SIMD (SSE2, NEON) or scalar code. For tests of both paths.
bool GreenDifferenceRowBaseline(const uint8_t* image, const uint8_t* background, int width,
                                int threshold, uint8_t* difference, uint64_t* over_threshold);

}  // namespace shapesense
