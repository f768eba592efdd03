#include "libs/centerline/silhouette_edges.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace shapesense {
namespace {

// Grey levels between body and backdrop below which an edge is not placed.
constexpr double kMinContrast = 8.0;
// Samples of the difference profile per pixel of the walk.
constexpr int kSubsteps = 2;

bool InsideWithMargin(const cv::Mat& image, const Vec2& p, double margin) {
  return p.x() >= margin && p.y() >= margin && p.x() <= image.cols - 1 - margin &&
         p.y() <= image.rows - 1 - margin;
}

bool MaskAt(const cv::Mat& mask, const Vec2& p) {
  // p is inside the image (x, y ≥ -0.5): adding 0.5 and truncating rounds.
  const int x = static_cast<int>(p.x() + 0.5);
  const int y = static_cast<int>(p.y() + 0.5);
  return mask.ptr<uint8_t>(y)[x] != 0;
}

// The profile of `difference` along the line, from 2.5 px inside the first
// masked-out pixel to 2.5 px beyond it, at kSubsteps samples per pixel.
constexpr int kProfileHalf = 5;  // samples each side of the exit
using Profile = std::array<double, 2 * kProfileHalf + 1>;

// Sub-pixel crossing of the half level, searched outward from inside; the
// distance of the exit pixel `exit` is the profile's centre.
std::optional<double> HalfLevelCrossing(const Profile& profile, double exit) {
  const double inside = std::max(profile[0], profile[1]);
  const double outside = std::min(profile[profile.size() - 1], profile[profile.size() - 2]);
  if (inside - outside < kMinContrast) return std::nullopt;
  const double half = 0.5 * (inside + outside);
  for (size_t k = 1; k < profile.size(); ++k) {
    if (profile[k - 1] >= half && profile[k] < half) {
      const double f = (profile[k - 1] - half) / (profile[k - 1] - profile[k]);
      const double sample = static_cast<double>(k - 1) + f - kProfileHalf;
      return exit + sample / kSubsteps;
    }
  }
  return std::nullopt;
}

}  // namespace

double SampleBilinear(const cv::Mat& image, const Vec2& position) {
  const int x = static_cast<int>(std::floor(position.x()));
  const int y = static_cast<int>(std::floor(position.y()));
  const double fx = position.x() - x;
  const double fy = position.y() - y;
  const uint8_t* row0 = image.ptr<uint8_t>(y) + x;
  const uint8_t* row1 = image.ptr<uint8_t>(y + 1) + x;
  const double top = row0[0] + fx * (row0[1] - row0[0]);
  const double bottom = row1[0] + fx * (row1[1] - row1[0]);
  return top + fy * (bottom - top);
}

std::optional<double> FindEdgeAlong(const Silhouette& silhouette, const Vec2& start,
                                    const Vec2& direction, int max_steps) {
  const cv::Mat& mask = silhouette.mask;
  // The profile reaches 2.5 px past the exit and bilinear sampling one more.
  const double margin = static_cast<double>(kProfileHalf) / kSubsteps + 1.5;
  if (!InsideWithMargin(mask, start, 0.0) || !MaskAt(mask, start)) return std::nullopt;
  int exit = 0;
  for (int k = 1; k <= max_steps && exit == 0; ++k) {
    const Vec2 p = start + k * direction;
    if (!InsideWithMargin(mask, p, margin)) return std::nullopt;
    if (!MaskAt(mask, p)) exit = k;
  }
  if (exit == 0) return std::nullopt;
  Profile profile;
  for (int s = 0; s < static_cast<int>(profile.size()); ++s) {
    const double along = exit + static_cast<double>(s - kProfileHalf) / kSubsteps;
    const Vec2 p = start + std::max(0.0, along) * direction;
    profile[static_cast<size_t>(s)] = SampleBilinear(silhouette.difference, p);
  }
  return HalfLevelCrossing(profile, exit);
}

}  // namespace shapesense
