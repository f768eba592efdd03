#include "libs/silhouette/tape_colour.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "libs/core/error.h"

namespace shapesense {
namespace {

// The rule's constants, as the header states it.
constexpr int kBins = 360;  // 1° of hue each
// The peak is found on counts summed over ± this many bins: noise splits a
// tape's hues over a few neighbouring bins.
constexpr int kPeakHalfWidth = 2;
constexpr double kTailFraction = 0.02;
constexpr double kSpreadFactor = 1.5;
constexpr double kMinHalfWidthDeg = 10.0;
constexpr double kMaxHalfWidthDeg = 90.0;
constexpr double kPercentile = 0.01;
constexpr double kMinimumMargin = 0.8;

struct TapePixel {
  double hue_deg;
  double saturation;
  int value;
};

// The bins from peak - below to peak + above, around the circle.
struct HueCluster {
  int peak;
  int below;
  int above;
};

// a - b in degrees, wrapped into [-180, 180).
double HueOffset(double a, double b) {
  const double offset = std::fmod(a - b + 540.0, 360.0);
  return offset - 180.0;
}

double WrapHue(double hue) { return std::fmod(std::fmod(hue, 360.0) + 360.0, 360.0); }

// The element at floor(q × (n - 1)) of the values in order.
double Quantile(std::vector<double> values, double q) {
  const auto at =
      values.begin() + static_cast<ptrdiff_t>(q * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

// The pixels the prior labelled tape, away from the silhouette's outline:
// there the tape mixes with the backdrop and its hue drifts towards yellow.
std::vector<TapePixel> InteriorTapePixels(const cv::Mat& image, const Silhouette& silhouette) {
  cv::Mat interior;
  cv::erode(silhouette.mask, interior, cv::Mat());  // 3×3
  std::vector<TapePixel> pixels;
  for (const RowRun& run : silhouette.runs) {
    const uint8_t* label = silhouette.labels.ptr<uint8_t>(run.y);
    const uint8_t* inside = interior.ptr<uint8_t>(run.y);
    const uint8_t* row = image.ptr<uint8_t>(run.y);
    for (int x = run.x0; x < run.x1; ++x) {
      if (label[x] != kLabelMarker || inside[x] == 0) continue;
      const uint8_t* bgr = row + ptrdiff_t{3} * x;
      pixels.push_back({HueDeg(bgr), Saturation(bgr), std::max({bgr[0], bgr[1], bgr[2]})});
    }
  }
  return pixels;
}

std::array<int64_t, kBins> SmoothedHistogram(const std::vector<TapePixel>& pixels) {
  std::array<int64_t, kBins> counts{};
  for (const TapePixel& pixel : pixels) ++counts[static_cast<size_t>(pixel.hue_deg) % kBins];
  std::array<int64_t, kBins> smoothed{};
  for (int bin = 0; bin < kBins; ++bin) {
    for (int k = -kPeakHalfWidth; k <= kPeakHalfWidth; ++k) {
      smoothed[static_cast<size_t>(bin)] += counts[static_cast<size_t>((bin + k + kBins) % kBins)];
    }
  }
  return smoothed;
}

// The highest bin and its neighbours on either side down to kTailFraction of it.
HueCluster FindCluster(const std::array<int64_t, kBins>& smoothed) {
  const int peak =
      static_cast<int>(std::max_element(smoothed.begin(), smoothed.end()) - smoothed.begin());
  const double tail = kTailFraction * static_cast<double>(smoothed[static_cast<size_t>(peak)]);
  const auto extent = [&](int step) {
    int bins = 0;
    while (bins < kBins / 2 - 1 &&
           static_cast<double>(
               smoothed[static_cast<size_t>((peak + step * (bins + 1) + kBins) % kBins)]) >= tail) {
      ++bins;
    }
    return bins;
  };
  return {peak, extent(-1), extent(1)};
}

std::vector<TapePixel> ClusterMembers(const std::vector<TapePixel>& pixels,
                                      const HueCluster& cluster) {
  std::vector<TapePixel> members;
  for (const TapePixel& pixel : pixels) {
    const int bin = static_cast<int>(pixel.hue_deg) % kBins;
    const int offset = (bin - cluster.peak + kBins + kBins / 2) % kBins - kBins / 2;
    if (offset >= -cluster.below && offset <= cluster.above) members.push_back(pixel);
  }
  return members;
}

std::vector<double> HueOffsets(const std::vector<TapePixel>& members, double from) {
  std::vector<double> offsets;
  offsets.reserve(members.size());
  for (const TapePixel& member : members) offsets.push_back(HueOffset(member.hue_deg, from));
  return offsets;
}

// The members' median hue, measured from the peak bin's centre so that a
// cluster across 0° has one.
double ClusterCentre(const std::vector<TapePixel>& members, const HueCluster& cluster) {
  const double peak_centre = cluster.peak + 0.5;
  return WrapHue(peak_centre + Quantile(HueOffsets(members, peak_centre), 0.5));
}

std::array<double, 2> LearntHueRange(const std::vector<TapePixel>& members, double centre) {
  const std::vector<double> offsets = HueOffsets(members, centre);
  const double below = std::clamp(-kSpreadFactor * Quantile(offsets, kPercentile), kMinHalfWidthDeg,
                                  kMaxHalfWidthDeg);
  const double above = std::clamp(kSpreadFactor * Quantile(offsets, 1.0 - kPercentile),
                                  kMinHalfWidthDeg, kMaxHalfWidthDeg);
  return {WrapHue(std::floor(centre - below)), WrapHue(std::ceil(centre + above))};
}

TapeColour LearntColour(const std::vector<TapePixel>& members, double centre) {
  std::vector<double> saturations, values;
  saturations.reserve(members.size());
  values.reserve(members.size());
  for (const TapePixel& member : members) {
    saturations.push_back(member.saturation);
    values.push_back(member.value);
  }
  TapeColour colour;
  colour.hue_deg = LearntHueRange(members, centre);
  // Rounded down to 0.01, and above 0 as Validate() asks.
  colour.min_saturation = std::max(
      0.01, std::floor(100.0 * kMinimumMargin * Quantile(saturations, kPercentile)) / 100.0);
  colour.min_value =
      static_cast<int>(std::floor(kMinimumMargin * Quantile(std::move(values), kPercentile)));
  return colour;
}

int64_t CountTape(const cv::Mat& image, const Silhouette& silhouette, const TapeColour& colour) {
  const TapeClassifier classifier(colour);
  int64_t tape = 0;
  for (const RowRun& run : silhouette.runs) {
    const uint8_t* pixel = image.ptr<uint8_t>(run.y) + ptrdiff_t{3} * run.x0;
    for (int x = run.x0; x < run.x1; ++x, pixel += 3) tape += classifier.IsTape(pixel);
  }
  return tape;
}

void CheckPrior(const Silhouette& silhouette, const SilhouetteOptions& options) {
  if (silhouette.area == 0) {
    throw InputError(
        "no silhouette: no pixel's green differs from the background's by more "
        "than the threshold (" +
        std::to_string(options.threshold) +
        " grey levels) outside shadows; is the manipulator in view, and the "
        "background the same camera's?");
  }
  if (cv::countNonZero(silhouette.labels == kLabelMarker) == 0) {
    throw InputError("the tape hue range " + Describe(options.tape) +
                     " matches no pixel of the silhouette (" + std::to_string(silhouette.area) +
                     " pixels)");
  }
}

void CheckEnough(const std::vector<TapePixel>& members, const Silhouette& silhouette,
                 const SilhouetteOptions& options) {
  if (static_cast<int64_t>(members.size()) >= kMinTapeColourPixels) return;
  throw InputError(
      "too few pixels to learn the tape colour from: " + std::to_string(members.size()) +
      " in the tape's hue cluster away from the silhouette's outline, at least " +
      std::to_string(kMinTapeColourPixels) + " needed (the tape hue range " +
      Describe(options.tape) + " matches " +
      std::to_string(cv::countNonZero(silhouette.labels == kLabelMarker)) +
      " pixels of the silhouette)");
}

}  // namespace

LearntTapeColour LearnTapeColour(const cv::Mat& image, const cv::Mat& background,
                                 const SilhouetteOptions& options) {
  Silhouette silhouette;
  SilhouetteExtractor(options).Extract(image, background, &silhouette);
  CheckPrior(silhouette, options);
  const std::vector<TapePixel> pixels = InteriorTapePixels(image, silhouette);
  const HueCluster cluster = FindCluster(SmoothedHistogram(pixels));
  const std::vector<TapePixel> members = ClusterMembers(pixels, cluster);
  CheckEnough(members, silhouette, options);
  LearntTapeColour learnt;
  learnt.peak_hue_deg = ClusterCentre(members, cluster);
  learnt.colour = LearntColour(members, learnt.peak_hue_deg);
  learnt.pixels = static_cast<int64_t>(members.size());
  learnt.labelled = CountTape(image, silhouette, learnt.colour);
  learnt.silhouette = silhouette.area;
  return learnt;
}

}  // namespace shapesense
