#include "libs/viz/overlay.h"

#include <algorithm>
#include <array>
#include <opencv2/imgproc.hpp>

namespace shapesense {
namespace {

const cv::Scalar kYellow(0, 230, 255);
const cv::Scalar kGreen(60, 220, 60);
const cv::Scalar kCyan(255, 220, 0);
const cv::Scalar kMagenta(255, 0, 255);
const cv::Scalar kRed(40, 40, 255);
const cv::Scalar kWhite(255, 255, 255);

// Projects a polyline into the camera; points behind it break the line.
void DrawProjected(cv::Mat& canvas, const Camera& camera, const Polyline& points,
                   const cv::Scalar& color, int thickness) {
  std::vector<cv::Point> run;
  auto flush = [&] {
    if (run.size() >= 2) cv::polylines(canvas, run, false, color, thickness, cv::LINE_AA);
    run.clear();
  };
  for (const Vec3& p : points) {
    const auto pixel = camera.Project(p);
    if (!pixel) {
      flush();
      continue;
    }
    run.emplace_back(static_cast<int>(std::lround(pixel->x())),
                     static_cast<int>(std::lround(pixel->y())));
  }
  flush();
}

}  // namespace

cv::Mat DrawCameraOverlay(const cv::Mat& image, const Silhouette& silhouette, const Camera& camera,
                          const ShapeEstimate& shape, const Polyline* truth) {
  cv::Mat canvas = image.clone();
  if (!silhouette.labels.empty()) canvas.setTo(kMagenta, silhouette.labels == kLabelMarker);
  if (!silhouette.mask.empty()) {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(silhouette.mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    cv::drawContours(canvas, contours, -1, kCyan, 1, cv::LINE_AA);
  }
  if (truth != nullptr) DrawProjected(canvas, camera, *truth, kGreen, 1);
  if (shape.valid) {
    DrawProjected(canvas, camera, shape.centerline, kYellow, 2);
    for (const Vec3& marker : shape.markers) {
      if (const auto pixel = camera.Project(marker)) {
        cv::circle(canvas, cv::Point2d(pixel->x(), pixel->y()), 6, kRed, 2, cv::LINE_AA);
      }
    }
  }
  cv::putText(canvas, camera.name + (shape.valid ? "" : "  (no shape: " + shape.error + ")"),
              cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.55, kWhite, 1, cv::LINE_AA);
  return canvas;
}

namespace {

// One orthogonal view: world axes (a, b) drawn right and up.
struct View {
  int a;
  int b;
  const char* name;
};

// The square region of a view that holds the body with a margin, mm.
struct ViewWindow {
  double low_a = 0.0;
  double low_b = 0.0;
  double extent = 1.0;
};

ViewWindow FitWindow(const VoxelCloud& cloud, const ShapeEstimate& shape, const Polyline* truth,
                     const View& view) {
  Eigen::AlignedBox3d box;
  for (const int32_t index : cloud.voxels) box.extend(cloud.grid.Center(int64_t{index}));
  for (const Vec3& p : shape.centerline) box.extend(p);
  if (truth != nullptr) {
    for (const Vec3& p : *truth) box.extend(p);
  }
  if (box.isEmpty()) box.extend(cloud.grid.origin);
  constexpr double kMargin = 15.0;  // mm
  const Vec3 center = box.center();
  const double extent = std::max(box.sizes()[view.a], box.sizes()[view.b]) + 2.0 * kMargin;
  return {center[view.a] - extent / 2.0, center[view.b] - extent / 2.0, extent};
}

cv::Mat DrawView(const VoxelCloud& cloud, const ShapeEstimate& shape, const Polyline* truth,
                 const View& view, int size_px) {
  const VoxelGrid& grid = cloud.grid;
  const ViewWindow window = FitWindow(cloud, shape, truth, view);
  const double scale = size_px / window.extent;
  auto to_pixel = [&](const Vec3& p) {
    return cv::Point2d((p[view.a] - window.low_a) * scale,
                       size_px - (p[view.b] - window.low_b) * scale);
  };
  cv::Mat canvas(size_px, size_px, CV_8UC3, cv::Scalar(30, 30, 30));
  const int dot = std::max(1, static_cast<int>(grid.voxel_size * scale));
  for (size_t i = 0; i < cloud.voxels.size(); ++i) {
    const cv::Point2d p = to_pixel(grid.Center(int64_t{cloud.voxels[i]}));
    const bool marker = !cloud.labels.empty() && cloud.labels[i] == kLabelMarker;
    cv::rectangle(canvas, cv::Rect(static_cast<int>(p.x), static_cast<int>(p.y), dot, dot),
                  marker ? cv::Scalar(60, 60, 200) : cv::Scalar(150, 150, 150), cv::FILLED);
  }
  auto draw_line = [&](const Polyline& line, const cv::Scalar& color, int thickness) {
    std::vector<cv::Point> points;
    for (const Vec3& p : line) points.emplace_back(to_pixel(p));
    if (points.size() >= 2) cv::polylines(canvas, points, false, color, thickness, cv::LINE_AA);
  };
  if (truth != nullptr) draw_line(*truth, kGreen, 1);
  if (shape.valid) draw_line(shape.centerline, kYellow, 1);
  const std::array<const char*, 3> axis = {"x", "y", "z"};
  cv::putText(canvas,
              std::string(view.name) + "  (" + axis[view.a] + " right, " + axis[view.b] + " up)",
              cv::Point(6, 18), cv::FONT_HERSHEY_SIMPLEX, 0.45, kWhite, 1, cv::LINE_AA);
  const int bar = static_cast<int>(10.0 * scale);
  cv::line(canvas, cv::Point(10, size_px - 12), cv::Point(10 + bar, size_px - 12), kWhite, 2);
  cv::putText(canvas, "10 mm", cv::Point(14 + bar, size_px - 8), cv::FONT_HERSHEY_SIMPLEX, 0.4,
              kWhite, 1, cv::LINE_AA);
  return canvas;
}

}  // namespace

cv::Mat DrawOrthogonalViews(const VoxelCloud& cloud, const ShapeEstimate& shape,
                            const Polyline* truth, int view_size_px) {
  const std::array<View, 3> views = {View{0, 1, "top"}, View{0, 2, "front"}, View{1, 2, "side"}};
  std::vector<cv::Mat> tiles;
  for (const View& view : views) tiles.push_back(DrawView(cloud, shape, truth, view, view_size_px));
  return TileImages(tiles, 3);
}

cv::Mat TileImages(const std::vector<cv::Mat>& images, int columns) {
  if (images.empty()) return {};
  int tile_w = 0;
  int tile_h = 0;
  for (const cv::Mat& image : images) {
    tile_w = std::max(tile_w, image.cols);
    tile_h = std::max(tile_h, image.rows);
  }
  const int count = static_cast<int>(images.size());
  const int cols = std::min(columns, count);
  const int rows = (count + cols - 1) / cols;
  cv::Mat canvas(rows * tile_h, cols * tile_w, images.front().type(), cv::Scalar::all(0));
  for (int i = 0; i < count; ++i) {
    const cv::Mat& image = images[static_cast<size_t>(i)];
    image.copyTo(
        canvas(cv::Rect((i % cols) * tile_w, (i / cols) * tile_h, image.cols, image.rows)));
  }
  return canvas;
}

}  // namespace shapesense
