#include "libs/silhouette/compact_silhouette.h"

#include <algorithm>
#include <cstring>

namespace shapesense {
namespace {

// Appends the runs of [x0, x1) of row y where `inside(x)` holds.
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

// Row arithmetic on sorted, disjoint runs [x0, x1) of one row (y unused).

// `runs` sorted by x0, merged where they overlap or touch.
void MergeInPlace(std::vector<RowRun>* runs) {
  std::sort(runs->begin(), runs->end(),
            [](const RowRun& a, const RowRun& b) { return a.x0 < b.x0; });
  size_t kept = 0;
  for (const RowRun& run : *runs) {
    if (kept > 0 && run.x0 <= (*runs)[kept - 1].x1) {
      (*runs)[kept - 1].x1 = std::max((*runs)[kept - 1].x1, run.x1);
    } else {
      (*runs)[kept++] = run;
    }
  }
  runs->resize(kept);
}

void Intersect(const std::vector<RowRun>& a, const std::vector<RowRun>& b,
               std::vector<RowRun>* out) {
  out->clear();
  size_t i = 0;
  size_t j = 0;
  while (i < a.size() && j < b.size()) {
    const int x0 = std::max(a[i].x0, b[j].x0);
    const int x1 = std::min(a[i].x1, b[j].x1);
    if (x0 < x1) out->push_back({0, x0, x1});
    (a[i].x1 < b[j].x1 ? i : j) += 1;
  }
}

// Appends row y of `a` minus `b` to `out`.
void AppendDifference(int y, const std::vector<RowRun>& a, const std::vector<RowRun>& b,
                      std::vector<RowRun>* out) {
  size_t j = 0;
  for (const RowRun& run : a) {
    int x = run.x0;
    while (j < b.size() && b[j].x1 <= x) ++j;
    for (size_t k = j; k < b.size() && b[k].x0 < run.x1; ++k) {
      if (b[k].x0 > x) out->push_back({y, x, b[k].x0});
      x = std::max(x, b[k].x1);
    }
    if (x < run.x1) out->push_back({y, x, run.x1});
  }
}

// The band: pixels within kEdgeBandRadius (Chebyshev) of a mask pixel and of
// a pixel of the image outside the mask, row by row from the mask's runs:
// the mask grown by the radius (the union of the nearby rows' runs widened)
// minus the mask shrunk by it (the intersection of the nearby rows' runs
// narrowed). Outside the image counts as neither, so the image's border is
// not an outline: a run touching it is not narrowed there, and rows beyond
// the image do not shrink the mask.
void CompactBand(const Silhouette& silhouette, CompactSilhouette* out, CompactScratch* scratch) {
  out->band.clear();
  out->band_difference.clear();
  const std::vector<RowRun>& runs = silhouette.runs;
  if (runs.empty()) return;
  const int r = kEdgeBandRadius;
  const int width = silhouette.mask.cols;
  const int height = silhouette.mask.rows;
  std::vector<int>& row_begin = scratch->row_begin;
  row_begin.assign(static_cast<size_t>(height) + 1, 0);
  for (const RowRun& run : runs) ++row_begin[static_cast<size_t>(run.y) + 1];
  for (int y = 0; y < height; ++y) row_begin[y + 1] += row_begin[y];
  const auto row = [&](int y) {
    return std::pair{runs.begin() + row_begin[y], runs.begin() + row_begin[y + 1]};
  };
  for (int y = std::max(0, runs.front().y - r); y <= std::min(height - 1, runs.back().y + r); ++y) {
    const int first = std::max(0, y - r);
    const int last = std::min(height - 1, y + r);
    scratch->grown.clear();
    for (int v = first; v <= last; ++v) {
      for (auto [it, end] = row(v); it != end; ++it) {
        scratch->grown.push_back({y, std::max(0, it->x0 - r), std::min(width, it->x1 + r)});
      }
    }
    if (scratch->grown.empty()) continue;
    MergeInPlace(&scratch->grown);
    scratch->shrunk.clear();
    for (int v = first; v <= last; ++v) {
      scratch->next.clear();
      for (auto [it, end] = row(v); it != end; ++it) {
        const int x0 = it->x0 == 0 ? 0 : it->x0 + r;
        const int x1 = it->x1 == width ? width : it->x1 - r;
        if (x0 < x1) scratch->next.push_back({y, x0, x1});
      }
      if (v == first) {
        scratch->shrunk.swap(scratch->next);
      } else {
        Intersect(scratch->shrunk, scratch->next, &scratch->narrowed);
        scratch->shrunk.swap(scratch->narrowed);
      }
      if (scratch->shrunk.empty()) break;
    }
    const size_t before = out->band.size();
    AppendDifference(y, scratch->grown, scratch->shrunk, &out->band);
    const uint8_t* difference = silhouette.difference.ptr<uint8_t>(y);
    for (size_t k = before; k < out->band.size(); ++k) {
      out->band_difference.insert(out->band_difference.end(), difference + out->band[k].x0,
                                  difference + out->band[k].x1);
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
  // An earlier expansion into `out` wrote only within its bounds and the band
  // around them: clearing that is enough (a tenth of the image, typically).
  const bool reused = out->mask.size() == size && out->labels.size() == size &&
                      out->difference.size() == size && out->mask.type() == CV_8U;
  const int margin = kEdgeBandRadius + 1;
  const cv::Rect written =
      reused ? (out->bounds + cv::Point(-margin, -margin) + cv::Size(2 * margin, 2 * margin)) &
                   cv::Rect(cv::Point(), size)
             : cv::Rect(cv::Point(), size);
  for (cv::Mat* image : {&out->mask, &out->labels, &out->difference}) {
    image->create(size, CV_8U);
    (*image)(written).setTo(0);
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
