#include "follow_bot_common/camera_mounting.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <opencv2/core/quaternion.hpp>

namespace follow_bot_common {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSidewaysToleranceM = 0.01;  // a sideways offset worth a warning
constexpr double kSameMountingTolerance = 1e-9;

double degrees(double rad) { return rad * 180.0 / kPi; }

}  // namespace

cv::Matx33d rotationOfQuaternion(const cv::Vec4d& xyzw) {
  return cv::Quatd(xyzw[3], xyzw[0], xyzw[1], xyzw[2]).toRotMat3x3();
}

std::string mountingFromTransform(const cv::Vec3d& origin, const cv::Matx33d& rotation,
                                  double base_height_m, CameraGeometry& camera,
                                  std::string& warning) {
  const cv::Vec3d right(rotation(0, 0), rotation(1, 0), rotation(2, 0));  // optical x
  const cv::Vec3d axis(rotation(0, 2), rotation(1, 2), rotation(2, 2));   // optical z
  const double horizontal = std::hypot(axis[0], axis[1]);
  const double pitch = std::atan2(-axis[2], horizontal);
  // Yaw and roll as they would be measured from a camera that only pitches: the axis's heading,
  // and the image's right against the horizontal right of that heading (about the axis).
  const double yaw = std::atan2(axis[1], axis[0]);
  const cv::Vec3d level_right(std::sin(yaw), -std::cos(yaw), 0.0);
  const cv::Vec3d level_down = axis.cross(level_right);
  const double roll = std::atan2(right.dot(level_down), right.dot(level_right));

  std::ostringstream problem;
  const double tolerance = kMountingToleranceDeg * kPi / 180.0;
  if (!(std::isfinite(origin[0]) && std::isfinite(origin[1]) && std::isfinite(origin[2]) &&
        std::isfinite(base_height_m) && std::isfinite(pitch) && std::isfinite(roll))) {
    return "the transform is not finite";
  }
  if (std::abs(yaw) > tolerance && horizontal > 1e-6) {
    problem << "the optical axis is yawed " << degrees(yaw)
            << " deg from the base's x axis (at most " << kMountingToleranceDeg
            << " deg: a camera looking straight ahead)";
    return problem.str();
  }
  if (std::abs(roll) > tolerance) {
    problem << "the camera is rolled " << degrees(roll) << " deg about its optical axis (at most "
            << kMountingToleranceDeg << " deg: image x to the robot's right, y down, REP 103)";
    return problem.str();
  }
  CameraGeometry mounted = camera;
  mounted.height_m = origin[2] + base_height_m;
  mounted.pitch_rad = pitch;
  mounted.x_offset_m = origin[0];
  std::string invalid = validate(mounted);
  if (!invalid.empty()) return invalid;
  warning.clear();
  if (std::abs(origin[1]) > kSidewaysToleranceM) {
    std::ostringstream sideways;
    sideways << "the camera is " << origin[1]
             << " m to the side of the base's centre line; taken as on it (a lateral bias of as "
                "much in the ground points)";
    warning = sideways.str();
  }
  camera = mounted;
  return "";
}

std::string describeMounting(const CameraGeometry& camera) {
  // Rounded to the 0.1 deg printed, then + 0.0: a pitch a hair below level reads 0.0, not -0.0.
  const double pitch_deg = std::round(degrees(camera.pitch_rad) * 10.0) / 10.0 + 0.0;
  char text[128];
  std::snprintf(text, sizeof text, "height %.3f m, pitch %.1f deg down, x offset %.3f m",
                camera.height_m, pitch_deg, camera.x_offset_m);
  return text;
}

bool sameMounting(const CameraGeometry& a, const CameraGeometry& b) {
  return std::abs(a.height_m - b.height_m) < kSameMountingTolerance &&
         std::abs(a.pitch_rad - b.pitch_rad) < kSameMountingTolerance &&
         std::abs(a.x_offset_m - b.x_offset_m) < kSameMountingTolerance;
}

}  // namespace follow_bot_common
