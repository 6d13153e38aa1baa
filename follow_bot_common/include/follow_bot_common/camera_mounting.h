// The camera's mounting (CameraGeometry's height, pitch and forward offset) from where tf puts
// its optical frame in the robot's base frame.
//
// The optical frame follows REP 103's camera convention: z forward along the optical axis, x to
// the image's right, y down. CameraGeometry models a camera on the robot's centre line looking
// straight ahead and tilted only in pitch (ground_projection.h), so a mounting with a visible
// roll or yaw is rejected rather than silently projected wrong.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "follow_bot_common/ground_projection.h"

namespace follow_bot_common {

// The largest roll or yaw of the optical frame still taken as zero: a URDF rounding or a small
// measuring error, well below what would bias the ground projection by more than ~1 cm at 1 m.
constexpr double kMountingToleranceDeg = 1.0;

// The state a behaviour reports while its camera's mounting is not known yet (it holds still).
constexpr const char* kWaitingForMountingState = "waiting for camera mounting";

// The rotation matrix of a quaternion given as tf does, (x, y, z, w); normalised first.
cv::Matx33d rotationOfQuaternion(const cv::Vec4d& xyzw);

// The mounting of a camera whose optical frame sits at `origin` with axes `rotation` (columns:
// the optical x, y, z axes) in the base frame, that base frame being `base_height_m` above the
// floor. Returns "" and sets `camera`'s height_m, pitch_rad and x_offset_m (its intrinsics
// untouched), or a message saying why the mounting cannot be used (`camera` unchanged). A
// sideways offset cannot be modelled and is ignored: `warning` then says by how much.
std::string mountingFromTransform(const cv::Vec3d& origin, const cv::Matx33d& rotation,
                                  double base_height_m, CameraGeometry& camera,
                                  std::string& warning);

// "height 0.300 m, pitch 20.0 deg down, x offset 0.000 m": for logs.
std::string describeMounting(const CameraGeometry& camera);

// Whether two geometries have the same mounting (intrinsics not compared).
bool sameMounting(const CameraGeometry& a, const CameraGeometry& b);

}  // namespace follow_bot_common
