// The pictures: what they mark and where.
#include "libs/calibration/calibration_drawing.h"

#include <gtest/gtest.h>

namespace shapesense {
namespace {

bool HasColourNear(const cv::Mat& image, const Vec2& at, const cv::Vec3b& colour, int reach) {
  for (int y = static_cast<int>(at.y()) - reach; y <= static_cast<int>(at.y()) + reach; ++y) {
    for (int x = static_cast<int>(at.x()) - reach; x <= static_cast<int>(at.x()) + reach; ++x) {
      if (x < 0 || y < 0 || x >= image.cols || y >= image.rows) continue;
      const cv::Vec3b& p = image.at<cv::Vec3b>(y, x);
      if (std::abs(p[0] - colour[0]) + std::abs(p[1] - colour[1]) + std::abs(p[2] - colour[2]) < 60)
        return true;
    }
  }
  return false;
}

TEST(CalibrationDrawingTest, OverlayMarksCornersReprojectionsAndLeftOutViews) {
  const cv::Mat grey(240, 320, CV_8UC1, cv::Scalar(128));
  BoardObservation seen;
  seen.ids = {0, 1, 2};
  seen.pixels = {Vec2(100, 150), Vec2(140, 150), Vec2(180, 150)};
  const std::vector<Vec2> reprojected = {Vec2(102, 150), Vec2(140, 151), Vec2(180, 150)};
  const cv::Mat used = DrawCornerOverlay(grey, seen, reprojected, "view 1", false);
  ASSERT_EQ(used.type(), CV_8UC3);
  ASSERT_EQ(used.size(), grey.size());
  EXPECT_TRUE(HasColourNear(used, Vec2(140, 146), cv::Vec3b(60, 200, 60), 1));   // green circle
  EXPECT_TRUE(HasColourNear(used, Vec2(180, 150), cv::Vec3b(40, 40, 230), 1));   // red cross
  EXPECT_TRUE(HasColourNear(used, Vec2(140, 158), cv::Vec3b(0, 220, 255), 1));   // error x10
  EXPECT_FALSE(HasColourNear(used, Vec2(300, 230), cv::Vec3b(40, 40, 230), 5));  // no red frame
  const cv::Mat left_out = DrawCornerOverlay(grey, seen, {}, "view 2", true);
  EXPECT_TRUE(HasColourNear(left_out, Vec2(318, 230), cv::Vec3b(40, 40, 230), 2));
  EXPECT_FALSE(HasColourNear(left_out, Vec2(180, 150), cv::Vec3b(40, 40, 230), 1));
}

TEST(CalibrationDrawingTest, RegistrationPlotDrawsABarPerAxisPerPoint) {
  PointRegistration registration;
  const std::vector<Vec3> reference = {Vec3(0, 0, 0), Vec3(100, 0, 0), Vec3(0, 100, 0)};
  registration.errors = {Vec3(0.5, 0, 0), Vec3(0, -0.5, 0), Vec3(0, 0, 0.5)};
  registration.rms_per_axis = Vec3::Constant(0.5 / std::sqrt(3.0));
  registration.rms = 0.5;
  registration.max_error = 0.5;
  const cv::Mat plot = DrawRegistrationPlot(reference, registration);
  ASSERT_EQ(plot.type(), CV_8UC3);
  int red = 0, green = 0, blue = 0;
  for (int y = 0; y < plot.rows; ++y) {
    for (int x = 0; x < 600; ++x) {
      const cv::Vec3b& p = plot.at<cv::Vec3b>(y, x);
      red += p == cv::Vec3b(40, 40, 230) ? 1 : 0;
      green += p == cv::Vec3b(60, 200, 60) ? 1 : 0;
      blue += p == cv::Vec3b(230, 120, 30) ? 1 : 0;
    }
  }
  // One full-height bar of each colour (0.5 mm is the axis limit).
  EXPECT_GT(red, 1000);
  EXPECT_GT(green, 1000);
  EXPECT_GT(blue, 1000);
}

}  // namespace
}  // namespace shapesense
