#pragma once

// A silhouette reduced to what the shape estimate reads of it, small enough
// to travel between processes and hosts in one datagram (the carving service
// sends it to the shape service: docs/architecture.md).
//
// The shape estimate reads three things of a Silhouette (libs/centerline):
//  - the mask, along walks from inside it to where it ends;
//  - the labels, body or tape, at pixels inside the mask;
//  - the difference image, in a profile of ±2.5 px (plus one pixel of
//    bilinear interpolation) around the first pixel where such a walk left
//    the mask. Every pixel of such a profile lies within kEdgeBandRadius
//    (Chebyshev) of a mask pixel and of a pixel outside the mask.
// The mask and the tape go as runs, the difference image only over that band
// along the outline. Expanding gives back the mask, labels and runs exactly
// and the difference image exactly on the band (0 elsewhere), so the shape
// measured from the expansion is the one measured from the original
// (compact_silhouette_test checks this on whole shape estimates).
#include <cstdint>
#include <string>
#include <vector>

#include "libs/silhouette/silhouette.h"

namespace shapesense {

// Chebyshev distance from the outline within which the difference image is
// kept, px. The profile of FindEdgeAlong reaches 4 px from the first pixel
// outside the mask and 5 px from the last inside.
inline constexpr int kEdgeBandRadius = 5;

struct CompactSilhouette {
  int width = 0;
  int height = 0;
  std::vector<RowRun> mask;              // the mask's runs, raster order
  std::vector<RowRun> markers;           // the tape's runs (inside the mask), raster order
  std::vector<RowRun> band;              // the pixels near the outline, raster order
  std::vector<uint8_t> band_difference;  // the difference image over `band`'s pixels, in order
};

// Working memory of Compact, kept by the caller so repeated calls allocate nothing.
struct CompactScratch {
  std::vector<int> row_begin;  // the mask's first run of each row
  std::vector<RowRun> grown;   // one row of the mask grown by kEdgeBandRadius
  std::vector<RowRun> shrunk;  // ... and shrunk by it
  std::vector<RowRun> next;
  std::vector<RowRun> narrowed;
};

// `silhouette` as extracted (mask, labels, difference, bounds and runs filled).
void Compact(const Silhouette& silhouette, CompactSilhouette* out, CompactScratch* scratch);

// "" when `compact` is well formed: a positive size, every run inside the
// image, non-empty and in raster order without overlap, the tape inside the
// mask, one difference value per band pixel. Else what is wrong.
std::string Validate(const CompactSilhouette& compact);

// The silhouette back, at full size; `compact` must pass Validate. The
// buffers of `out` are reused: `out` must be empty or an earlier Expand's,
// which wrote only near its mask, so only that part is cleared (an
// extracted silhouette's difference image covers the whole image).
void Expand(const CompactSilhouette& compact, Silhouette* out);

}  // namespace shapesense
