#include "image_converter/overlay.h"

#include <gtest/gtest.h>

#include <cmath>

namespace image_converter {
namespace {

const cv::Vec3b kGrey(90, 100, 110);
const cv::Vec3b kRed(0, 0, 255);

TEST(Overlay, DrawsARedRingOfTheConfiguredRadiusAtTheCentre) {
  cv::Mat image(120, 200, CV_8UC3, cv::Scalar(kGrey[0], kGrey[1], kGrey[2]));
  const OverlayConfig config;  // radius 25, thickness 2
  ASSERT_TRUE(drawOverlay(image, config));

  const double cx = image.cols / 2, cy = image.rows / 2;
  int changed = 0;
  double sum_x = 0, sum_y = 0;
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      const cv::Vec3b pixel = image.at<cv::Vec3b>(r, c);
      if (pixel == kGrey) continue;
      ++changed;
      sum_x += c;
      sum_y += r;
      EXPECT_EQ(pixel, kRed) << "at " << c << "," << r;
      const double distance = std::hypot(c - cx, r - cy);
      EXPECT_NEAR(distance, config.radius_px, config.thickness_px) << "at " << c << "," << r;
    }
  }
  // OpenCV's 8-connected thick outline is thickness..thickness+1 pixels wide: a ring of
  // radius 25 covers between 2*pi*25*2 ~ 314 and 2*pi*25*3 ~ 471 pixels.
  EXPECT_GT(changed, 300);
  EXPECT_LT(changed, 500);
  EXPECT_NEAR(sum_x / changed, cx, 0.5);
  EXPECT_NEAR(sum_y / changed, cy, 0.5);
  EXPECT_EQ(image.at<cv::Vec3b>(cy, cx + config.radius_px), kRed);
  EXPECT_EQ(image.at<cv::Vec3b>(cy, cx), kGrey);
}

TEST(Overlay, SkipsImagesNotLargerThanTheMinimum) {
  cv::Mat small(50, 50, CV_8UC3, cv::Scalar(kGrey[0], kGrey[1], kGrey[2]));
  const cv::Mat before = small.clone();
  EXPECT_FALSE(drawOverlay(small, OverlayConfig{}));
  EXPECT_EQ(cv::norm(small, before, cv::NORM_INF), 0.0);

  cv::Mat just_larger(51, 51, CV_8UC3, cv::Scalar(kGrey[0], kGrey[1], kGrey[2]));
  EXPECT_TRUE(drawOverlay(just_larger, OverlayConfig{}));
}

TEST(Overlay, ValidatesItsConfiguration) {
  EXPECT_TRUE(isValid(OverlayConfig{}));
  EXPECT_FALSE(isValid(OverlayConfig{0, 2, 50}));
  EXPECT_FALSE(isValid(OverlayConfig{25, 0, 50}));
  EXPECT_FALSE(isValid(OverlayConfig{25, 2, -1}));
  EXPECT_EQ(validate(OverlayConfig{25, 0, 50}), "thickness_px must be > 0, got 0");
}

}  // namespace
}  // namespace image_converter
