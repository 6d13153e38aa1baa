#include "follow_bot_common/ground_projection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "follow_bot_common/testing/harness_camera.h"

namespace follow_bot_common {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(GroundProjection, CentrePixelLandsOnTheOpticalAxis) {
  for (double pitch_deg : {5.0, 20.0, 45.0, 80.0}) {
    CameraGeometry camera = harnessCamera();
    camera.pitch_rad = degrees(pitch_deg);
    camera.x_offset_m = 0.12;
    const auto ground = pixelToGround(camera, camera.cx, camera.cy);
    ASSERT_TRUE(ground) << pitch_deg;
    EXPECT_NEAR(ground->x, 0.12 + 0.3 / std::tan(camera.pitch_rad), 1e-12) << pitch_deg;
    EXPECT_NEAR(ground->y, 0.0, 1e-15);
  }
}

TEST(GroundProjection, HandComputedOffAxisPixel) {
  // Pitch 45 deg, 1 m up, one focal length right of centre: the optical ray (1, 0, 1) is
  // (cos 45, -1, -sin 45) in base_link and meets the floor after sqrt(2): at (1, -sqrt(2)).
  CameraGeometry camera = harnessCamera();
  camera.pitch_rad = degrees(45.0);
  camera.height_m = 1.0;
  const auto ground = pixelToGround(camera, camera.cx + camera.fx, camera.cy);
  ASSERT_TRUE(ground);
  EXPECT_NEAR(ground->x, 1.0, 1e-12);
  EXPECT_NEAR(ground->y, -std::sqrt(2.0), 1e-12);
}

TEST(GroundProjection, ImageRightIsRobotRightAndLowerRowsAreCloser) {
  const CameraGeometry camera = harnessCamera();
  const auto right = pixelToGround(camera, 500.0, 370.0);
  const auto left = pixelToGround(camera, 100.0, 370.0);
  const auto lower = pixelToGround(camera, 320.0, 470.0);
  const auto centre = pixelToGround(camera, 320.0, 370.0);
  ASSERT_TRUE(right && left && lower && centre);
  EXPECT_LT(right->y, 0.0);
  EXPECT_GT(left->y, 0.0);
  EXPECT_NEAR(right->x, left->x, 1e-12) << "a row maps to a line across the robot";
  EXPECT_LT(lower->x, centre->x);
}

TEST(GroundProjection, TheLectureBandSeesAboutHalfAMetreAhead) {
  // Rows 360..379 of the harness camera: centroid row 369.5, angle 20 + atan(129.5 / fy) deg.
  const auto ground = pixelToGround(harnessCamera(), 320.0, 369.5);
  ASSERT_TRUE(ground);
  EXPECT_NEAR(ground->x, 0.3 / std::tan(degrees(20.0) + std::atan(129.5 / 554.256)), 1e-12);
  EXPECT_NEAR(ground->x, 0.459, 0.001);
}

TEST(GroundProjection, NothingAtOrAboveTheHorizon) {
  const CameraGeometry camera = harnessCamera();
  const double horizon_row = camera.cy - camera.fy * std::tan(camera.pitch_rad);
  EXPECT_FALSE(pixelToGround(camera, 320.0, horizon_row - 1.0));
  EXPECT_FALSE(pixelToGround(camera, 320.0, 0.0));
  const auto just_below = pixelToGround(camera, 320.0, horizon_row + 0.5);
  ASSERT_TRUE(just_below);
  EXPECT_GT(just_below->x, 10.0);

  CameraGeometry level = camera;
  level.pitch_rad = 0.0;
  EXPECT_FALSE(pixelToGround(level, 320.0, level.cy));
  EXPECT_TRUE(pixelToGround(level, 320.0, level.cy + 1.0));

  CameraGeometry looking_up = camera;
  looking_up.pitch_rad = degrees(-10.0);
  EXPECT_FALSE(pixelToGround(looking_up, 320.0, 300.0));
  EXPECT_TRUE(pixelToGround(looking_up, 320.0, 479.0));
}

TEST(GroundProjection, NonFiniteInputHasNoGroundPoint) {
  const CameraGeometry camera = harnessCamera();
  EXPECT_FALSE(pixelToGround(camera, kNaN, 400.0));
  EXPECT_FALSE(pixelToGround(camera, 320.0, kNaN));
  EXPECT_FALSE(pixelToGround(camera, std::numeric_limits<double>::infinity(), 400.0));
}

TEST(GroundProjection, RoundTripsWithAnIndependentProjection) {
  CameraGeometry camera;
  camera.fx = 600.0;
  camera.fy = 580.0;
  camera.cx = 331.5;
  camera.cy = 229.25;
  camera.height_m = 0.42;
  camera.x_offset_m = -0.07;
  for (double pitch_deg : {-20.0, 0.0, 12.0, 35.0, 70.0}) {
    camera.pitch_rad = degrees(pitch_deg);
    for (double u = 0.0; u < 640.0; u += 37.5) {
      for (double v = 0.0; v < 480.0; v += 21.25) {
        const auto ground = pixelToGround(camera, u, v);
        if (!ground) {
          // Only pixels at or above the horizon miss the floor.
          EXPECT_LE(v, camera.cy - camera.fy * std::tan(camera.pitch_rad) + 1e-9);
          continue;
        }
        const cv::Point3d pixel = projectToPixel(camera, *ground);
        EXPECT_GT(pixel.z, 0.0);
        EXPECT_NEAR(pixel.x, u, 1e-6) << pitch_deg << " " << u << " " << v;
        EXPECT_NEAR(pixel.y, v, 1e-6) << pitch_deg << " " << u << " " << v;
      }
    }
  }
}

TEST(GroundProjection, ValidateNamesTheBadField) {
  EXPECT_EQ(validate(harnessCamera()), "");
  EXPECT_EQ(validate(CameraGeometry()), "") << "the defaults are the harness camera";
  CameraGeometry camera = harnessCamera();
  camera.fx = 0.0;
  EXPECT_NE(validate(camera).find("fx"), std::string::npos);
  camera = harnessCamera();
  camera.fy = kNaN;
  EXPECT_NE(validate(camera).find("fy"), std::string::npos);
  camera = harnessCamera();
  camera.cy = std::numeric_limits<double>::infinity();
  EXPECT_NE(validate(camera).find("cy"), std::string::npos);
  camera = harnessCamera();
  camera.height_m = -0.3;
  EXPECT_NE(validate(camera).find("height_m"), std::string::npos);
  camera = harnessCamera();
  camera.pitch_rad = degrees(89.5);
  EXPECT_NE(validate(camera).find("pitch_rad"), std::string::npos);
  camera.pitch_rad = degrees(-89.5);
  EXPECT_NE(validate(camera).find("pitch_rad"), std::string::npos);
  camera.pitch_rad = degrees(88.0);
  EXPECT_EQ(validate(camera), "");
  camera.x_offset_m = kNaN;
  EXPECT_NE(validate(camera).find("x_offset_m"), std::string::npos);
}

// The harness's turtlebot3 lens (harness/src/harness/camera.py): visible barrel distortion.
CameraGeometry barrelCamera() {
  CameraGeometry camera = harnessCamera();
  const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  camera.lens = CameraLens{k, {-0.28, 0.07, 0.0, 0.0, 0.0}, cv::Matx33d::eye()};
  return camera;
}

TEST(RectifyPixels, WithoutALensPixelsAreUnchanged) {
  const std::vector<cv::Point2d> raw = {{0.0, 0.0}, {319.5, 240.25}, {639.0, 479.0}};
  EXPECT_EQ(rectifyPixels(harnessCamera(), raw), raw);
  EXPECT_EQ(rectifyPixel(harnessCamera(), {12.5, 400.0}), cv::Point2d(12.5, 400.0));
}

TEST(RectifyPixels, UndoesTheLensToTheRectifiedPinhole) {
  // Rays through the whole frame, corners included: cv::projectPoints with K and D puts each
  // where the lens images it; rectified, it must land where the pinhole (P = K) puts it.
  const CameraGeometry camera = barrelCamera();
  std::vector<cv::Point3d> rays;
  for (double x = -0.7; x <= 0.7; x += 0.1) {
    for (double y = -0.5; y <= 0.5; y += 0.1) rays.emplace_back(x, y, 1.0);
  }
  std::vector<cv::Point2d> raw;
  cv::projectPoints(rays, cv::Vec3d(), cv::Vec3d(), camera.lens->camera_matrix,
                    camera.lens->distortion, raw);
  const std::vector<cv::Point2d> rectified = rectifyPixels(camera, raw);
  ASSERT_EQ(rectified.size(), rays.size());
  double moved = 0.0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const cv::Point2d pinhole(camera.cx + camera.fx * rays[i].x, camera.cy + camera.fy * rays[i].y);
    EXPECT_NEAR(rectified[i].x, pinhole.x, 1e-6) << rays[i];
    EXPECT_NEAR(rectified[i].y, pinhole.y, 1e-6) << rays[i];
    moved = std::max(moved, cv::norm(raw[i] - pinhole));
  }
  EXPECT_GT(moved, 20.0) << "the lens must matter for this test to mean anything";
  // The float overload (the sign's keypoints) agrees to float precision.
  const std::vector<cv::Point2f> raw32(raw.begin(), raw.end());
  const std::vector<cv::Point2f> rectified32 = rectifyPixels(camera, raw32);
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_NEAR(rectified32[i].x, rectified[i].x, 1e-3);
    EXPECT_NEAR(rectified32[i].y, rectified[i].y, 1e-3);
  }
}

TEST(RectifyPixels, RectifiedIntrinsicsMayDifferFromTheRawOnes) {
  // P != K (a calibration's new camera matrix): rectified pixels are P's.
  CameraGeometry camera = barrelCamera();
  camera.fx = camera.fy = 500.0;
  camera.cx = 310.0;
  const cv::Point3d ray(0.3, -0.2, 1.0);
  std::vector<cv::Point2d> raw;
  cv::projectPoints(std::vector<cv::Point3d>{ray}, cv::Vec3d(), cv::Vec3d(),
                    camera.lens->camera_matrix, camera.lens->distortion, raw);
  const cv::Point2d rectified = rectifyPixel(camera, raw.front());
  EXPECT_NEAR(rectified.x, 310.0 + 500.0 * 0.3, 1e-6);
  EXPECT_NEAR(rectified.y, 240.0 - 500.0 * 0.2, 1e-6);
}

TEST(RectifyPixels, ValidateRejectsABrokenLens) {
  EXPECT_EQ(validate(barrelCamera()), "");
  CameraGeometry camera = barrelCamera();
  camera.lens->distortion = {-0.28, 0.07, 0.0};
  EXPECT_NE(validate(camera).find("lens D"), std::string::npos) << validate(camera);
  camera.lens->distortion = {kNaN, 0.07, 0.0, 0.0, 0.0};
  EXPECT_NE(validate(camera).find("lens D"), std::string::npos);
  camera = barrelCamera();
  camera.lens->camera_matrix(0, 0) = 0.0;
  EXPECT_NE(validate(camera).find("lens K fx"), std::string::npos);
  camera = barrelCamera();
  camera.lens->rectification(0, 1) = 0.5;
  EXPECT_NE(validate(camera).find("lens R"), std::string::npos);
  camera.lens->rectification = cv::Matx33d::eye() * kNaN;
  EXPECT_NE(validate(camera).find("lens R"), std::string::npos);
}

// A frame half the calibrated size (binning 2, a resized stream) sees each floor point at half
// the pixel, through the lens too; another aspect ratio has no intrinsics.
TEST(IntrinsicsForFrame, ScalesWithTheFrameAndRejectsAnotherAspect) {
  const CameraGeometry camera = barrelCamera();
  const cv::Size calibrated(640, 480);
  const std::optional<CameraGeometry> same = intrinsicsForFrame(camera, calibrated, calibrated);
  ASSERT_TRUE(same);
  EXPECT_EQ(same->fx, camera.fx);
  EXPECT_EQ(same->lens->camera_matrix, camera.lens->camera_matrix);
  EXPECT_TRUE(intrinsicsForFrame(camera, cv::Size(), cv::Size(320, 240)));

  const std::optional<CameraGeometry> half = intrinsicsForFrame(camera, calibrated, {320, 240});
  ASSERT_TRUE(half);
  EXPECT_EQ(validate(*half), "");
  EXPECT_DOUBLE_EQ(half->fx, camera.fx / 2);
  EXPECT_DOUBLE_EQ(half->cy, camera.cy / 2);
  EXPECT_DOUBLE_EQ(half->lens->camera_matrix(1, 2), camera.lens->camera_matrix(1, 2) / 2);
  EXPECT_EQ(half->lens->camera_matrix(2, 2), 1.0);
  EXPECT_EQ(half->height_m, camera.height_m);
  const cv::Point2d raw(100.0, 400.0);
  const cv::Point2d rectified = rectifyPixel(camera, raw);
  const cv::Point2d rectified_half = rectifyPixel(*half, raw / 2);
  EXPECT_NEAR(rectified_half.x, rectified.x / 2, 1e-9);
  EXPECT_NEAR(rectified_half.y, rectified.y / 2, 1e-9);
  const std::optional<cv::Point2d> floor = pixelToGround(camera, 320.0, 400.0);
  const std::optional<cv::Point2d> floor_half = pixelToGround(*half, 160.0, 200.0);
  ASSERT_TRUE(floor && floor_half);
  EXPECT_NEAR(floor_half->x, floor->x, 1e-12);

  EXPECT_TRUE(intrinsicsForFrame(camera, calibrated, {1280, 960}));
  EXPECT_FALSE(intrinsicsForFrame(camera, calibrated, {1280, 720}));
  EXPECT_FALSE(intrinsicsForFrame(camera, calibrated, {320, 241}));
}

}  // namespace
}  // namespace follow_bot_common
