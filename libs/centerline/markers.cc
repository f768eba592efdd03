#include "libs/centerline/markers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <utility>

#include "libs/centerline/curve_measures.h"
#include "libs/geometry/polyline.h"
#include "libs/silhouette/silhouette.h"

namespace shapesense {
namespace {

struct Cluster {
  Vec3 sum = Vec3::Zero();
  int count = 0;
};

MarkerOnCurve PlaceOnCurve(const Cluster& cluster, const Polyline& centerline,
                           const std::vector<double>& arc, double voxel_size) {
  const ClosestPoint closest = ClosestPointOnPolyline(centerline, arc, cluster.sum / cluster.count);
  MarkerOnCurve marker;
  marker.arc_length = closest.arc_length;
  marker.point = closest.point;
  marker.voxels = cluster.count;
  marker.std_mm = voxel_size;
  return marker;
}

// Lines of the tube's surface read in each view, spread over ±kMaxLineAngle
// about the one facing the camera: farther out the line nears the outline,
// where a bilinear read would mix in the backdrop.
constexpr int kLines = 5;
constexpr double kMaxLineAngle = 0.25 * std::numbers::pi;
// Along a line the pixels are projected exactly this far apart and
// interpolated between (the image of a line on the tube is smooth on this
// scale), mm.
constexpr double kProjectStep = 3.0;
// Labels are read this far apart along a line's image to find the band,
// px; its edges are then refined by bisection.
constexpr double kReadStepPx = 0.8;
// Without a configured width, bands of these widths are accepted, mm.
constexpr double kMinUnknownWidth = 1.0;
constexpr double kMaxUnknownWidth = 12.0;
// A view needs this many lines that agree.
constexpr int kMinLines = 3;
// A line's edge is off by up to half a pixel (the labels are binary); the
// centre averages two edges: about 0.2 px standard error.
constexpr double kCentreQuantisationPx = 0.2;
// Views of one band that differ by more than this many standard errors, and
// by more than kMinDisagreement mm, saw different things.
constexpr double kMaxNormalisedDisagreement = 4.0;
constexpr double kMinDisagreement = 0.3;

// Where one band is looked for: arc lengths [first, last] about the seed.
struct BandWindow {
  double first = 0.0;
  double last = 0.0;
  double seed = 0.0;
  double width = 0.0;  // configured, or 0
};

// One view's reading of a band.
struct ViewBand {
  double center = 0.0;
  double width = 0.0;
  double standard_error = 0.0;  // of the centre, mm
};

// The tube's cross-section at arc s as a camera sees it: the axis point, and
// the unit vectors towards the camera (across the axis) and sideways.
struct Section {
  Vec3 axis = Vec3::Zero();
  Vec3 towards = Vec3::Zero();
  Vec3 across = Vec3::Zero();
};

Section SectionAt(const Polyline& centerline, const std::vector<double>& arc, double s,
                  const Vec3& camera_center) {
  Section section;
  section.axis = PointAtArcLength(centerline, arc, s);
  const Vec3 tangent = ChordTangent(centerline, arc, s, 0.5);
  const Vec3 to_camera = camera_center - section.axis;
  section.towards = (to_camera - to_camera.dot(tangent) * tangent).normalized();
  section.across = tangent.cross(section.towards);
  return section;
}

// The share of tape around a sub-pixel point: the labels of the four nearest
// pixels (tape 1, body 0) interpolated bilinearly; nullopt when one of them
// is off the body or outside the image.
std::optional<double> TapeShare(const cv::Mat& labels, const Vec2& pixel) {
  const int x0 = static_cast<int>(std::floor(pixel.x()));
  const int y0 = static_cast<int>(std::floor(pixel.y()));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= labels.cols || y0 + 1 >= labels.rows) return std::nullopt;
  const uint8_t* top = labels.ptr<uint8_t>(y0) + x0;
  const uint8_t* bottom = labels.ptr<uint8_t>(y0 + 1) + x0;
  if (top[0] == kLabelNone || top[1] == kLabelNone || bottom[0] == kLabelNone ||
      bottom[1] == kLabelNone) {
    return std::nullopt;
  }
  const auto tape = [](uint8_t label) { return label == kLabelMarker ? 1.0 : 0.0; };
  const double fx = pixel.x() - x0;
  const double fy = pixel.y() - y0;
  return (1.0 - fy) * ((1.0 - fx) * tape(top[0]) + fx * tape(top[1])) +
         fy * ((1.0 - fx) * tape(bottom[0]) + fx * tape(bottom[1]));
}

// The images of the window's surface lines, at nodes every kProjectStep:
// the axis's pixel and the pixel offsets of r·towards and r·across, so that
// the line at angle φ passes through axis + cos φ·towards + sin φ·across.
// (Over a radius the projection is affine to a few hundredths of a pixel,
// so three projections per node serve every line.)
struct LineImages {
  std::vector<double> node_arc;
  std::vector<Vec2> axis;
  std::vector<Vec2> towards;
  std::vector<Vec2> across;
  std::vector<bool> valid;
  std::vector<Vec3> front;  // the surface point facing the camera, world

  Vec2 Pixel(size_t node, double cosine, double sine) const {
    return axis[node] + cosine * towards[node] + sine * across[node];
  }
};

LineImages ProjectLines(const Camera& camera, const Polyline& centerline,
                        const std::vector<double>& arc, const BandWindow& window, double radius) {
  LineImages images;
  const Vec3 c = camera.Center();
  const int nodes =
      std::max(1, static_cast<int>(std::ceil((window.last - window.first) / kProjectStep)));
  for (int k = 0; k <= nodes; ++k) {
    const double s = window.first + (window.last - window.first) * k / nodes;
    const Section section = SectionAt(centerline, arc, s, c);
    const std::optional<Vec2> axis = camera.Project(section.axis);
    const std::optional<Vec2> towards = camera.Project(section.axis + radius * section.towards);
    const std::optional<Vec2> across = camera.Project(section.axis + radius * section.across);
    const bool valid = axis && towards && across;
    images.node_arc.push_back(s);
    images.axis.push_back(valid ? *axis : Vec2::Zero());
    images.towards.push_back(valid ? Vec2(*towards - *axis) : Vec2::Zero());
    images.across.push_back(valid ? Vec2(*across - *axis) : Vec2::Zero());
    images.valid.push_back(valid);
    images.front.push_back(section.axis + radius * section.towards);
  }
  return images;
}

// Pixels per mm along the tube's facing line at the window's middle.
double PixelsPerMm(const LineImages& images) {
  const size_t middle = images.axis.size() / 2;
  if (middle == 0 || !images.valid[middle] || !images.valid[middle - 1]) return 0.0;
  const double span = images.node_arc[middle] - images.node_arc[middle - 1];
  return (images.Pixel(middle, 1.0, 0.0) - images.Pixel(middle - 1, 1.0, 0.0)).norm() / span;
}

// The tape share along one surface line, at any arc length of the window:
// NaN where the line cannot be read (outside the image, off the body, or
// behind another part of the tube).
class LineReader {
 public:
  LineReader(const cv::Mat& labels, const LineImages& images, const std::vector<bool>& hidden,
             double angle)
      : labels_(labels),
        images_(images),
        hidden_(hidden),
        cosine_(std::cos(angle)),
        sine_(std::sin(angle)),
        first_(images.node_arc.front()),
        spacing_(images.node_arc[1] - images.node_arc[0]) {}

  double ShareAt(double s) const {
    constexpr double kUnreadable = std::numeric_limits<double>::quiet_NaN();
    const double u = (s - first_) / spacing_;
    const size_t last = images_.node_arc.size() - 1;
    const size_t k = std::min(static_cast<size_t>(std::max(u, 0.0)), last - 1);
    const auto nearest = std::min(static_cast<size_t>(std::lround(std::max(u, 0.0))), last);
    if (!images_.valid[k] || !images_.valid[k + 1] || hidden_[nearest]) return kUnreadable;
    const double f = u - static_cast<double>(k);
    const Vec2 pixel =
        (1.0 - f) * images_.Pixel(k, cosine_, sine_) + f * images_.Pixel(k + 1, cosine_, sine_);
    return TapeShare(labels_, pixel).value_or(kUnreadable);
  }

 private:
  const cv::Mat& labels_;
  const LineImages& images_;
  const std::vector<bool>& hidden_;
  double cosine_;
  double sine_;
  double first_;
  double spacing_;
};

// Where the share crosses one half between `outside` (< 0.5) and `inside`
// (>= 0.5), a few bisections then linearly; nullopt when a read fails.
std::optional<double> Crossing(const LineReader& line, double outside, double inside) {
  constexpr int kBisections = 3;
  double a = line.ShareAt(outside);
  double b = line.ShareAt(inside);
  for (int i = 0; i < kBisections; ++i) {
    const double middle = 0.5 * (outside + inside);
    const double value = line.ShareAt(middle);
    if (std::isnan(value)) return std::nullopt;
    if (value >= 0.5) {
      inside = middle;
      b = value;
    } else {
      outside = middle;
      a = value;
    }
  }
  return outside + (inside - outside) * (0.5 - a) / (b - a);
}

// The run of tape nearest the seed on one line, read every `step` mm, its
// edges where the share crosses one half: [low, high] in mm, or nullopt when
// the run does not end on readable body at both sides within the window.
std::optional<std::pair<double, double>> EdgesOnLine(const LineReader& line,
                                                     const BandWindow& window, double step,
                                                     std::vector<double>* share) {
  // Read on demand, outwards from the seed: most of the window is never read.
  constexpr double kUnread = -1.0;
  const int n = static_cast<int>(std::floor((window.last - window.first) / step + 1e-9)) + 1;
  share->assign(static_cast<size_t>(n), kUnread);
  const auto read = [&](int k) {
    double& value = (*share)[static_cast<size_t>(k)];
    if (value == kUnread) value = line.ShareAt(window.first + step * k);
    return value;
  };
  const auto tape = [&](int k) { return read(k) >= 0.5; };
  const auto body = [&](int k) { return read(k) < 0.5; };  // NaN: neither
  const int guess = std::clamp(static_cast<int>(std::lround((window.seed - window.first) / step)),
                               0, std::max(n - 1, 0));
  int start = -1;
  for (int d = 0; d < n && start < 0; ++d) {
    if (guess - d >= 0 && tape(guess - d)) {
      start = guess - d;
    } else if (guess + d < n && tape(guess + d)) {
      start = guess + d;
    }
  }
  if (start < 0) return std::nullopt;
  int low = start;
  int high = start;
  while (low > 0 && tape(low - 1)) --low;
  while (high + 1 < n && tape(high + 1)) ++high;
  if (low == 0 || high == n - 1 || !body(low - 1) || !body(high + 1)) return std::nullopt;
  const auto at = [&](int k) { return window.first + step * k; };
  const std::optional<double> first = Crossing(line, at(low - 1), at(low));
  const std::optional<double> last = Crossing(line, at(high + 1), at(high));
  if (!first || !last) return std::nullopt;
  return std::make_pair(*first, *last);
}

bool PlausibleWidth(double width, const BandWindow& window, double mm_per_px) {
  if (window.width <= 0.0) return width >= kMinUnknownWidth && width <= kMaxUnknownWidth;
  return std::abs(width - window.width) <= 0.3 * window.width + 2.0 * mm_per_px;
}

// The centreline every kPartStep mm, to test what hides a band.
constexpr double kPartStep = 2.0;
struct TubeParts {
  std::vector<double> arc;
  std::vector<Vec3> point;
};

TubeParts PartsOf(const Polyline& centerline, const std::vector<double>& arc) {
  TubeParts parts;
  for (double t = 0.0; t <= arc.back(); t += kPartStep) {
    parts.arc.push_back(t);
    parts.point.push_back(PointAtArcLength(centerline, arc, t));
  }
  return parts;
}

double DistanceToSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double along = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - a - along * ab).norm();
}

// Which nodes of the window another part of the tube hides from the camera:
// the labels there are that part's. The rays start on the surface line
// facing the camera; a part whose axis passes within a radius of one enters
// the tube in front, and the lines read up to r·sin(kMaxLineAngle) to either
// side, so those are hidden too. The tube's own continuation is left out as
// far as a ray leaving its surface can pass near its axis: farther the more
// nearly the view runs along it.
std::vector<bool> HiddenNodes(const Camera& camera, const TubeParts& parts,
                              const LineImages& images, double radius, const Vec3& tangent) {
  const double reach = radius * (1.0 + std::sin(kMaxLineAngle)) + 0.5 * kPartStep + 0.2;
  const Vec3 c = camera.Center();
  const size_t middle = images.front.size() / 2;
  const Vec3 to_camera = (c - images.front[middle]).normalized();
  const double cosine = std::abs(tangent.dot(to_camera));
  const double sine = std::max(tangent.cross(to_camera).norm(), 0.2);
  const double keep_out = std::max(2.0 * radius, (reach - radius * cosine) / sine + kPartStep);
  const double first = images.node_arc.front();
  const double last = images.node_arc.back();
  // Only parts near the fan of rays from the camera to the window can hide it.
  const double fan = reach + 0.5 * (last - first) + kPartStep;
  std::vector<bool> hidden(images.front.size(), false);
  for (size_t p = 0; p < parts.arc.size(); ++p) {
    // The tube's own continuation, on either side of the whole window.
    const double t = parts.arc[p];
    if (t > first - keep_out && t < last + keep_out) continue;
    if (DistanceToSegment(parts.point[p], c, images.front[middle]) > fan) continue;
    for (size_t k = 0; k < images.front.size(); ++k) {
      if (hidden[k]) continue;
      const Vec3 ray = c - images.front[k];
      const Vec3 other = parts.point[p] - images.front[k];
      const double along = other.dot(ray) / ray.squaredNorm();
      hidden[k] = along > 0.0 && along < 1.0 && (other - along * ray).norm() < reach;
    }
  }
  return hidden;
}

// The view's centre from the lines that agree with their median (one
// crossing a stray label is dropped), its standard error from their spread
// and the labels' quantisation; nullopt with fewer than kMinLines.
std::optional<ViewBand> AgreeingLines(const std::vector<double>& centers,
                                      const std::vector<double>& widths, double mm_per_px) {
  if (static_cast<int>(centers.size()) < kMinLines) return std::nullopt;
  std::vector<double> sorted = centers;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2),
                   sorted.end());
  const double median = sorted[sorted.size() / 2];
  const double tolerance = std::max(0.3, 1.5 * mm_per_px);
  double sum = 0.0;
  double sum_sq = 0.0;
  double width_sum = 0.0;
  int count = 0;
  for (size_t i = 0; i < centers.size(); ++i) {
    if (std::abs(centers[i] - median) > tolerance) continue;
    sum += centers[i];
    sum_sq += centers[i] * centers[i];
    width_sum += widths[i];
    ++count;
  }
  if (count < kMinLines) return std::nullopt;
  const double mean = sum / count;
  const double spread_sq = std::max(0.0, sum_sq / count - mean * mean) * count / (count - 1);
  const double quantisation = kCentreQuantisationPx * mm_per_px;
  return ViewBand{mean, width_sum / count,
                  std::sqrt(spread_sq / count + quantisation * quantisation)};
}

// The band as one camera sees it; nullopt when it cannot be read there.
std::optional<ViewBand> ReadBandInView(const Camera& camera, const cv::Mat& labels,
                                       const Polyline& centerline, const std::vector<double>& arc,
                                       const TubeParts& parts, const BandWindow& window,
                                       double radius) {
  const LineImages images = ProjectLines(camera, centerline, arc, window, radius);
  const double px_per_mm = PixelsPerMm(images);
  if (px_per_mm < 0.2) return std::nullopt;  // along the line of sight: nothing to read
  const std::vector<bool> hidden =
      HiddenNodes(camera, parts, images, radius, ChordTangent(centerline, arc, window.seed, 1.0));
  const double mm_per_px = 1.0 / px_per_mm;
  const double step = std::min(kReadStepPx * mm_per_px, 0.5);
  std::vector<double> share;
  std::vector<double> centers;
  std::vector<double> widths;
  for (int k = 0; k < kLines; ++k) {
    const double angle = -kMaxLineAngle + 2.0 * kMaxLineAngle * k / (kLines - 1);
    const LineReader line(labels, images, hidden, angle);
    const std::optional<std::pair<double, double>> edges = EdgesOnLine(line, window, step, &share);
    if (!edges || !PlausibleWidth(edges->second - edges->first, window, mm_per_px)) continue;
    centers.push_back(0.5 * (edges->first + edges->second));
    widths.push_back(edges->second - edges->first);
  }
  return AgreeingLines(centers, widths, mm_per_px);
}

// The views fused by their inverse variances, dropping (with three or more)
// the one that disagrees most while any does; nullopt when what remains
// still disagrees: the band is ambiguous.
std::optional<MarkerOnCurve> FuseViews(std::vector<ViewBand> views) {
  while (!views.empty()) {
    double weights = 0.0;
    double center = 0.0;
    double width = 0.0;
    for (const ViewBand& v : views) {
      const double w = 1.0 / (v.standard_error * v.standard_error);
      weights += w;
      center += w * v.center;
      width += w * v.width;
    }
    center /= weights;
    width /= weights;
    const double standard_error = 1.0 / std::sqrt(weights);
    size_t worst = 0;
    double worst_score = 0.0;
    for (size_t i = 0; i < views.size(); ++i) {
      const double off = std::abs(views[i].center - center);
      const double score =
          off < kMinDisagreement ? 0.0 : off / std::hypot(views[i].standard_error, standard_error);
      if (score > worst_score) {
        worst_score = score;
        worst = i;
      }
    }
    if (worst_score <= kMaxNormalisedDisagreement) {
      MarkerOnCurve marker;
      marker.arc_length = center;
      marker.std_mm = standard_error;
      marker.width = width;
      marker.views = static_cast<int>(views.size());
      return marker;
    }
    if (views.size() < 3) return std::nullopt;
    views.erase(views.begin() + static_cast<long>(worst));
  }
  return std::nullopt;
}

// The largest cot θ over the cameras at arc s (θ between the axis and the
// direction to the camera), at least 1; views nearly along the axis are
// left to their own check (ReadBandInView).
double LargestFrontShiftPerRadius(const Rig& rig, const Polyline& centerline,
                                  const std::vector<double>& arc, double s) {
  constexpr double kMaxCotangent = 4.0;
  const Vec3 point = PointAtArcLength(centerline, arc, s);
  const Vec3 tangent = ChordTangent(centerline, arc, s, 1.0);
  double largest = 1.0;
  for (const Camera& camera : rig.cameras) {
    const Vec3 to_camera = (camera.Center() - point).normalized();
    const double cotangent =
        std::abs(tangent.dot(to_camera)) / std::max(tangent.cross(to_camera).norm(), 1e-6);
    largest = std::max(largest, std::min(cotangent, kMaxCotangent));
  }
  return largest;
}

std::optional<MarkerOnCurve> LocateBand(const Rig& rig, const std::vector<Silhouette>& silhouettes,
                                        const Polyline& centerline, const std::vector<double>& arc,
                                        const TubeParts& parts, double radius,
                                        const BandWindow& window) {
  std::vector<ViewBand> views;
  for (size_t k = 0; k < rig.cameras.size(); ++k) {
    const Camera& camera = rig.cameras[k];
    const cv::Mat& labels = silhouettes[k].labels;
    if (labels.type() != CV_8U || labels.cols != camera.width || labels.rows != camera.height) {
      continue;  // no labels (or not this camera's): no tape to read
    }
    if (const std::optional<ViewBand> view =
            ReadBandInView(camera, labels, centerline, arc, parts, window, radius)) {
      views.push_back(*view);
    }
  }
  return FuseViews(std::move(views));
}

}  // namespace

void LocateBandsInImages(const Rig& rig, const std::vector<Silhouette>& silhouettes,
                         const Polyline& centerline, const std::vector<double>& arc, double radius,
                         const BandPrior& prior, std::vector<MarkerOnCurve>* markers) {
  if (silhouettes.size() != rig.cameras.size() || centerline.size() < 2) return;
  const double half_width = 0.5 * (prior.width > 0.0 ? prior.width : kMaxUnknownWidth);
  const TubeParts parts = PartsOf(centerline, arc);
  std::vector<MarkerOnCurve> located;
  for (const MarkerOnCurve& seed : *markers) {
    const double half_reach =
        half_width + prior.seed_error +
        radius * LargestFrontShiftPerRadius(rig, centerline, arc, seed.arc_length);
    BandWindow window;
    window.seed = seed.arc_length;
    window.first = std::max(0.0, seed.arc_length - half_reach);
    window.last = std::min(arc.back(), seed.arc_length + half_reach);
    window.width = prior.width;
    std::optional<MarkerOnCurve> band =
        LocateBand(rig, silhouettes, centerline, arc, parts, radius, window);
    if (!band) continue;  // hidden or ambiguous: missing, not placed from voxels
    band->voxels = seed.voxels;
    band->arc_length = std::clamp(band->arc_length, 0.0, arc.back());
    band->point = PointAtArcLength(centerline, arc, band->arc_length);
    located.push_back(*band);
  }
  std::sort(located.begin(), located.end(), [](const MarkerOnCurve& a, const MarkerOnCurve& b) {
    return a.arc_length < b.arc_length;
  });
  // Two seeds of one band (a cluster split by a gap in its voxels) find it
  // twice; the better placed is kept.
  markers->clear();
  const double same_band = 0.5 * (prior.width > 0.0 ? prior.width : kMinUnknownWidth);
  for (const MarkerOnCurve& band : located) {
    if (!markers->empty() && band.arc_length - markers->back().arc_length < same_band) {
      if (band.std_mm < markers->back().std_mm) markers->back() = band;
      continue;
    }
    markers->push_back(band);
  }
}

std::vector<MarkerOnCurve> FindMarkers(const VoxelCloud& cloud, const VoxelGraph& graph,
                                       const GeodesicBody& body, const Polyline& centerline,
                                       const std::vector<double>& arc, int min_voxels, double gap) {
  std::vector<MarkerOnCurve> markers;
  if (centerline.size() < 2 || cloud.labels.size() != cloud.voxels.size()) return markers;
  Cluster cluster;
  double last_distance = 0.0;
  const auto close_cluster = [&] {
    if (cluster.count >= min_voxels)
      markers.push_back(PlaceOnCurve(cluster, centerline, arc, cloud.grid.voxel_size));
    cluster = Cluster();
  };
  for (const int32_t i : body.members) {
    if (cloud.labels[static_cast<size_t>(i)] != kLabelMarker) continue;
    const double distance = body.distance[static_cast<size_t>(i)];
    if (cluster.count > 0 && distance - last_distance > gap) close_cluster();
    cluster.sum += VoxelCenter(cloud.grid, graph.coordinates(i));
    ++cluster.count;
    last_distance = distance;
  }
  close_cluster();
  std::sort(markers.begin(), markers.end(), [](const MarkerOnCurve& a, const MarkerOnCurve& b) {
    return a.arc_length < b.arc_length;
  });
  return markers;
}

}  // namespace shapesense
