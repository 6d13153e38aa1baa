#include "follow_bot_common/camera_mounting.h"

#include <gtest/gtest.h>

#include <cmath>

namespace follow_bot_common {
namespace {

constexpr double kPi = 3.14159265358979323846;

double radians(double deg) { return deg * kPi / 180.0; }

// A URDF origin's rotation: fixed-axis roll, then pitch, then yaw (R = Rz * Ry * Rx).
cv::Matx33d rpy(double roll, double pitch, double yaw) {
  const double cr = std::cos(roll), sr = std::sin(roll);
  const double cp = std::cos(pitch), sp = std::sin(pitch);
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  const cv::Matx33d rx(1, 0, 0, 0, cr, -sr, 0, sr, cr);
  const cv::Matx33d ry(cp, 0, sp, 0, 1, 0, -sp, 0, cp);
  const cv::Matx33d rz(cy, -sy, 0, sy, cy, 0, 0, 0, 1);
  return rz * ry * rx;
}

// camera_link -> camera_rgb_optical_frame as every REP 103 camera description has it (and
// harness/robot_description.py): z forward, x right, y down.
const cv::Matx33d kLinkFromOptical = rpy(-kPi / 2, 0.0, -kPi / 2);

// base_link -> optical frame of a camera_link mounted with `roll`, `pitch` (down positive, as a
// URDF's rpy pitch) and `yaw`.
cv::Matx33d baseFromOptical(double roll_deg, double pitch_deg, double yaw_deg) {
  return rpy(radians(roll_deg), radians(pitch_deg), radians(yaw_deg)) * kLinkFromOptical;
}

TEST(CameraMounting, UrdfMountingsGiveTheirHeightPitchAndOffset) {
  for (double pitch_deg : {-10.0, 0.0, 10.0, 20.0, 30.0, 60.0}) {
    CameraGeometry camera;
    std::string warning;
    const std::string error = mountingFromTransform(
        cv::Vec3d(-0.087, 0.0, 0.2868), baseFromOptical(0, pitch_deg, 0), 0.0102, camera, warning);
    ASSERT_EQ(error, "") << pitch_deg;
    EXPECT_NEAR(camera.height_m, 0.297, 1e-12) << pitch_deg;
    EXPECT_NEAR(camera.pitch_rad, radians(pitch_deg), 1e-12) << pitch_deg;
    EXPECT_NEAR(camera.x_offset_m, -0.087, 1e-12) << pitch_deg;
    EXPECT_EQ(warning, "");
  }
}

TEST(CameraMounting, IntrinsicsAreKept) {
  CameraGeometry camera;
  camera.fx = 400.0;
  camera.cy = 100.0;
  std::string warning;
  ASSERT_EQ(
      mountingFromTransform(cv::Vec3d(0, 0, 0.4), baseFromOptical(0, 0, 0), 0.0, camera, warning),
      "");
  EXPECT_EQ(camera.fx, 400.0);
  EXPECT_EQ(camera.cy, 100.0);
}

// The transform's own rays, followed to the floor, land where pixelToGround puts their pixels:
// the helper and the projection agree on the conventions.
TEST(CameraMounting, AgreesWithTheGroundProjection) {
  const cv::Vec3d origin(0.12, 0.0, 0.25);
  const cv::Matx33d rotation = baseFromOptical(0, 25.0, 0);
  CameraGeometry camera;
  std::string warning;
  ASSERT_EQ(mountingFromTransform(origin, rotation, 0.05, camera, warning), "");
  for (const cv::Point2d pixel :
       {cv::Point2d(camera.cx, camera.cy), cv::Point2d(50, 470), cv::Point2d(600, 300)}) {
    const cv::Vec3d ray = rotation * cv::Vec3d((pixel.x - camera.cx) / camera.fx,
                                               (pixel.y - camera.cy) / camera.fy, 1.0);
    const double to_floor = (origin[2] + 0.05) / -ray[2];
    const auto ground = pixelToGround(camera, pixel.x, pixel.y);
    ASSERT_TRUE(ground);
    EXPECT_NEAR(ground->x, origin[0] + to_floor * ray[0], 1e-12);
    EXPECT_NEAR(ground->y, origin[1] + to_floor * ray[1], 1e-12);
  }
}

TEST(CameraMounting, RejectsYawAndRollBeyondTheTolerance) {
  CameraGeometry camera;
  const CameraGeometry before = camera;
  std::string warning;
  const cv::Vec3d origin(0, 0, 0.3);
  const std::string yawed =
      mountingFromTransform(origin, baseFromOptical(0, 20, 5), 0.0, camera, warning);
  EXPECT_NE(yawed.find("yawed 5"), std::string::npos) << yawed;
  const std::string rolled =
      mountingFromTransform(origin, baseFromOptical(-3, 20, 0), 0.0, camera, warning);
  EXPECT_NE(rolled.find("rolled"), std::string::npos) << rolled;
  EXPECT_NE(rolled.find("REP 103"), std::string::npos) << rolled;
  // Upside down: x left, y up. And an optical frame without the optical rotation (x forward).
  EXPECT_NE(mountingFromTransform(origin, baseFromOptical(180, 0, 0), 0.0, camera, warning), "");
  EXPECT_NE(mountingFromTransform(origin, rpy(0, 0, 0), 0.0, camera, warning), "");
  EXPECT_TRUE(sameMounting(camera, before));
  // Within the tolerance: a rounding, taken as zero.
  EXPECT_EQ(mountingFromTransform(origin, baseFromOptical(0.5, 20, -0.5), 0.0, camera, warning),
            "");
  EXPECT_NEAR(camera.pitch_rad, radians(20), radians(0.01));
}

TEST(CameraMounting, RejectsACameraAtOrBelowTheFloor) {
  CameraGeometry camera;
  std::string warning;
  const std::string error = mountingFromTransform(cv::Vec3d(0, 0, -0.01), baseFromOptical(0, 20, 0),
                                                  0.0, camera, warning);
  EXPECT_NE(error.find("height_m must be > 0"), std::string::npos) << error;
  EXPECT_DOUBLE_EQ(camera.height_m, CameraGeometry().height_m);
}

TEST(CameraMounting, WarnsOfASidewaysOffset) {
  CameraGeometry camera;
  std::string warning;
  ASSERT_EQ(mountingFromTransform(cv::Vec3d(0.1, -0.045, 0.3), baseFromOptical(0, 10, 0), 0.0,
                                  camera, warning),
            "");
  EXPECT_NE(warning.find("-0.045 m to the side"), std::string::npos) << warning;
  EXPECT_NEAR(camera.x_offset_m, 0.1, 1e-12);
}

TEST(CameraMounting, DescribesAndComparesMountings) {
  CameraGeometry camera;
  camera.height_m = 0.3;
  camera.pitch_rad = radians(20.0);
  camera.x_offset_m = -0.087;
  EXPECT_EQ(describeMounting(camera), "height 0.300 m, pitch 20.0 deg down, x offset -0.087 m");
  CameraGeometry level = camera;
  level.pitch_rad = -1e-17;  // a level URDF camera through tf's quaternion
  EXPECT_EQ(describeMounting(level), "height 0.300 m, pitch 0.0 deg down, x offset -0.087 m");
  CameraGeometry other = camera;
  other.fx = 1.0;
  EXPECT_TRUE(sameMounting(camera, other));
  other.pitch_rad += 1e-6;
  EXPECT_FALSE(sameMounting(camera, other));
}

}  // namespace
}  // namespace follow_bot_common
