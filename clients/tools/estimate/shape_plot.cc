#include "clients/tools/estimate/shape_plot.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "libs/mechanics/configuration_geometry.h"

namespace shapesense {
namespace {

const cv::Scalar kSensedColour(190, 90, 20);  // blue
const cv::Scalar kModelColour(0, 130, 255);   // orange
const cv::Scalar kInkColour(60, 60, 60);
constexpr int kMargin = 40;

// Distal section from the origin (its start), sampled every 2 mm.
Polyline DistalFromOrigin(const Configuration& q, const SectionLengths& rest) {
  Polyline points = DistalCenterline(q, rest, 2.0);
  const Vec3 start = points.front();
  for (Vec3& p : points) p -= start;
  return points;
}

struct View {
  int horizontal_axis;  // 0 = x, 2 = z; the vertical is always y
  std::string title;
};

// Millimetres to pixels, equal scale on both axes, y up.
struct Mapping {
  double scale = 1.0;
  Vec2 low = Vec2::Zero();
  int size = 0;

  cv::Point ToPixel(const Vec3& p, int horizontal_axis) const {
    const double u = kMargin + (p(horizontal_axis) - low.x()) * scale;
    const double v = size - kMargin - (p.y() - low.y()) * scale;
    return {static_cast<int>(std::lround(u)), static_cast<int>(std::lround(v))};
  }
};

Mapping FitView(const std::vector<Polyline>& shapes, int horizontal_axis, int size) {
  Vec2 low(0.0, 0.0), high(1.0, 1.0);
  for (const Polyline& shape : shapes) {
    for (const Vec3& p : shape) {
      low = low.cwiseMin(Vec2(p(horizontal_axis), p.y()));
      high = high.cwiseMax(Vec2(p(horizontal_axis), p.y()));
    }
  }
  Mapping mapping;
  mapping.size = size;
  mapping.scale = (size - 2.0 * kMargin) / (high - low).maxCoeff();
  // Centre the shorter extent.
  mapping.low = low - 0.5 * (Vec2::Constant((high - low).maxCoeff()) - (high - low));
  return mapping;
}

void DrawShapes(cv::Mat& panel, const std::vector<Polyline>& shapes, const Mapping& mapping,
                int horizontal_axis, const cv::Scalar& colour) {
  for (const Polyline& shape : shapes) {
    std::vector<cv::Point> pixels;
    for (const Vec3& p : shape) pixels.push_back(mapping.ToPixel(p, horizontal_axis));
    cv::polylines(panel, pixels, false, colour, 1, cv::LINE_AA);
  }
}

cv::Mat DrawPanel(const std::vector<Polyline>& sensed, const std::vector<Polyline>& predicted,
                  const View& view, const ShapePlotOptions& options) {
  cv::Mat panel(options.panel_size, options.panel_size, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<Polyline> all = sensed;
  all.insert(all.end(), predicted.begin(), predicted.end());
  const Mapping mapping = FitView(all, view.horizontal_axis, options.panel_size);
  DrawShapes(panel, sensed, mapping, view.horizontal_axis, kSensedColour);
  DrawShapes(panel, predicted, mapping, view.horizontal_axis, kModelColour);
  const auto text = [&](const std::string& s, int row, const cv::Scalar& colour) {
    cv::putText(panel, s, {10, 20 * row}, cv::FONT_HERSHEY_SIMPLEX, 0.5, colour, 1, cv::LINE_AA);
  };
  text(view.title, 1, kInkColour);
  text("sensed", 2, kSensedColour);
  text(options.model_label, 3, kModelColour);
  cv::rectangle(panel, {0, 0}, {options.panel_size - 1, options.panel_size - 1}, kInkColour);
  return panel;
}

}  // namespace

cv::Mat PlotSensedAgainstModel(const TendonModel& model, const std::vector<PoseSample>& poses,
                               const ShapePlotOptions& options) {
  std::vector<Polyline> sensed, predicted;
  for (const PoseSample& pose : poses) {
    sensed.push_back(DistalFromOrigin(pose.configuration, model.lengths()));
    predicted.push_back(DistalFromOrigin(model.Forward(pose.displacements), model.lengths()));
  }
  cv::Mat plot;
  cv::hconcat(DrawPanel(sensed, predicted, {0, "front: x (right) - y (up), mm"}, options),
              DrawPanel(sensed, predicted, {2, "side: z (right) - y (up), mm"}, options), plot);
  return plot;
}

}  // namespace shapesense
