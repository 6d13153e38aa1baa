#include "follow_bot/panorama_stitch.h"

#include <gtest/gtest.h>

namespace follow_bot {
namespace {

TEST(PanoramaStitch, ParsesTheThreeMethodsAndNothingElse) {
  EXPECT_EQ(parseStitchMethod("auto"), StitchMethod::kAuto);
  EXPECT_EQ(parseStitchMethod("features"), StitchMethod::kFeatures);
  EXPECT_EQ(parseStitchMethod("rotation"), StitchMethod::kRotation);
  EXPECT_FALSE(parseStitchMethod("Rotation"));
  EXPECT_FALSE(parseStitchMethod(""));
}

TEST(PanoramaStitch, FailsWithoutOneYawPerFrame) {
  const std::vector<cv::Mat> frames(2, cv::Mat(48, 64, CV_8UC3, cv::Scalar(0, 0, 0)));
  const CaptureStitch stitched =
      stitchCapture(frames, {0.0}, CameraGeometry(), {}, StitchMethod::kRotation);
  EXPECT_FALSE(stitched.ok());
  EXPECT_EQ(stitched.message, "stitching failed: no frames, or not one yaw per frame");
}

}  // namespace
}  // namespace follow_bot
