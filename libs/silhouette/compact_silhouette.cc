#include "libs/silhouette/compact_silhouette.h"

#include <algorithm>
#include <cstring>
#include <opencv2/imgproc.hpp>

namespace shapesense {
namespace {

// Appends the runs of `row[x0, x1)` where `inside(x)` holds, in row y.
template <class Predicate>
void AppendRuns(int y, int x0, int x1, Predicate inside, std::vector<RowRun>* runs) {
  int x = x0;
  while (x < x1) {
    while (x < x1 && !inside(x)) ++x;
    const int begin = x;
    while (x < x1 && inside(x)) ++x;
    if (x > begin) runs->push_back({y, begin, x});
  }
}

void CompactMarkers(const Silhouette& silhouette, std::vector<RowRun>* markers) {
  markers->clear();
  for (const RowRun& run : silhouette.runs) {
    const uint8_t* labels = silhouette.labels.ptr<uint8_t>(run.y);
    AppendRuns(
        run.y, run.x0, run.x1, [&](int x) { return labels[x] == kLabelMarker; }, markers);
  }
}

// The band: pixels within kEdgeBandRadius of a mask pixel and of a pixel
// outside it, i.e. in the mask grown by the radius and not in the mask
// shrunk by it. Outside the image counts as neither (OpenCV's default border
// for dilation and erosion), so the image's border is not an outline.
void CompactBand(const Silhouette& silhouette, CompactSilhouette* out, CompactScratch* scratch) {
  out->band.clear();
  out->band_difference.clear();
  if (silhouette.bounds.empty()) return;
  const int margin = kEdgeBandRadius + 1;
  const cv::Rect image(0, 0, silhouette.mask.cols, silhouette.mask.rows);
  const cv::Rect roi =
      (silhouette.bounds + cv::Point(-margin, -margin) + cv::Size(2 * margin, 2 * margin)) & image;
  const cv::Mat element = cv::getStructuringElement(
      cv::MORPH_RECT, cv::Size(2 * kEdgeBandRadius + 1, 2 * kEdgeBandRadius + 1));
  cv::dilate(silhouette.mask(roi), scratch->grown, element);
  cv::erode(silhouette.mask(roi), scratch->shrunk, element);
  for (int r = 0; r < roi.height; ++r) {
    const uint8_t* grown = scratch->grown.ptr<uint8_t>(r);
    const uint8_t* shrunk = scratch->shrunk.ptr<uint8_t>(r);
    const size_t first = out->band.size();
    AppendRuns(
        roi.y + r, 0, roi.width, [&](int x) { return grown[x] != 0 && shrunk[x] == 0; },
        &out->band);
    const uint8_t* difference = silhouette.difference.ptr<uint8_t>(roi.y + r);
    for (size_t k = first; k < out->band.size(); ++k) {
      RowRun& run = out->band[k];
      run.x0 += roi.x;
      run.x1 += roi.x;
      out->band_difference.insert(out->band_difference.end(), difference + run.x0,
                                  difference + run.x1);
    }
  }
}

// Runs inside the image, non-empty, in raster order without overlap.
std::string ValidateRuns(const std::vector<RowRun>& runs, int width, int height,
                         const std::string& what) {
  const RowRun* previous = nullptr;
  for (const RowRun& run : runs) {
    if (run.y < 0 || run.y >= height || run.x0 < 0 || run.x0 >= run.x1 || run.x1 > width) {
      return what + ": run [" + std::to_string(run.x0) + ", " + std::to_string(run.x1) +
             ") of row " + std::to_string(run.y) + " is empty or outside the " +
             std::to_string(width) + "x" + std::to_string(height) + " image";
    }
    if (previous != nullptr &&
        (run.y < previous->y || (run.y == previous->y && run.x0 < previous->x1))) {
      return what + ": runs out of raster order or overlapping at row " + std::to_string(run.y);
    }
    previous = &run;
  }
  return {};
}

// Every run of `inner` lies within one run of `outer` (both valid).
bool Contained(const std::vector<RowRun>& inner, const std::vector<RowRun>& outer) {
  size_t k = 0;
  for (const RowRun& run : inner) {
    while (k < outer.size() &&
           (outer[k].y < run.y || (outer[k].y == run.y && outer[k].x1 <= run.x0))) {
      ++k;
    }
    if (k == outer.size() || outer[k].y != run.y || outer[k].x0 > run.x0 || outer[k].x1 < run.x1) {
      return false;
    }
  }
  return true;
}

size_t PixelsIn(const std::vector<RowRun>& runs) {
  size_t pixels = 0;
  for (const RowRun& run : runs) pixels += static_cast<size_t>(run.x1 - run.x0);
  return pixels;
}

void Fill(cv::Mat& image, const std::vector<RowRun>& runs, uint8_t value) {
  for (const RowRun& run : runs) {
    std::memset(image.ptr<uint8_t>(run.y) + run.x0, value, static_cast<size_t>(run.x1 - run.x0));
  }
}

}  // namespace

void Compact(const Silhouette& silhouette, CompactSilhouette* out, CompactScratch* scratch) {
  out->width = silhouette.mask.cols;
  out->height = silhouette.mask.rows;
  out->mask = silhouette.runs;
  CompactMarkers(silhouette, &out->markers);
  CompactBand(silhouette, out, scratch);
}

std::string Validate(const CompactSilhouette& compact) {
  const int width = compact.width;
  const int height = compact.height;
  if (width <= 0 || height <= 0) {
    return "expected a positive image size, got " + std::to_string(width) + "x" +
           std::to_string(height);
  }
  for (const auto& [runs, what] :
       {std::pair{&compact.mask, "mask"}, std::pair{&compact.markers, "tape"},
        std::pair{&compact.band, "edge band"}}) {
    if (std::string error = ValidateRuns(*runs, width, height, what); !error.empty()) return error;
  }
  if (!Contained(compact.markers, compact.mask)) return "tape: a run lies outside the mask";
  if (PixelsIn(compact.band) != compact.band_difference.size()) {
    return "edge band: expected " + std::to_string(PixelsIn(compact.band)) +
           " difference values, got " + std::to_string(compact.band_difference.size());
  }
  return {};
}

void Expand(const CompactSilhouette& compact, Silhouette* out) {
  const cv::Size size(compact.width, compact.height);
  for (cv::Mat* image : {&out->mask, &out->labels, &out->difference}) {
    image->create(size, CV_8U);
    image->setTo(0);
  }
  Fill(out->mask, compact.mask, 255);
  Fill(out->labels, compact.mask, kLabelBody);
  Fill(out->labels, compact.markers, kLabelMarker);
  const uint8_t* value = compact.band_difference.data();
  for (const RowRun& run : compact.band) {
    const size_t length = static_cast<size_t>(run.x1 - run.x0);
    std::memcpy(out->difference.ptr<uint8_t>(run.y) + run.x0, value, length);
    value += length;
  }
  out->runs = compact.mask;
  out->area = static_cast<int64_t>(PixelsIn(compact.mask));
  out->bounds = cv::Rect();
  for (const RowRun& run : compact.mask) {
    out->bounds |= cv::Rect(run.x0, run.y, run.x1 - run.x0, 1);
  }
}

}  // namespace shapesense
