// Reading private parameters with validation: a bad value is a startup error naming it.
#pragma once

#include <cmath>

#include <ros/node_handle.h>

#include "follow_bot/ground_projection.h"
#include "image_converter/ros/params.h"

namespace follow_bot {

using image_converter::applyOrKeep;
using image_converter::checkedParam;
using image_converter::param;
using image_converter::positiveParam;
using image_converter::readConfig;

// The camera's mounting over `defaults`: ~camera_height (m, > 0), ~camera_pitch_deg (deg, down
// positive, within (-89, 89)), ~camera_x_offset (m, forward of base_link, finite). Intrinsics
// arrive later with camera_info. Throws std::invalid_argument naming the first bad value.
inline CameraGeometry readCameraMounting(const ros::NodeHandle& pnh, CameraGeometry defaults = {}) {
  CameraGeometry camera = defaults;
  camera.height_m = positiveParam(pnh, "camera_height", defaults.height_m);
  const double pitch_deg = checkedParam(
      pnh, "camera_pitch_deg", defaults.pitch_rad * 180.0 / M_PI,
      [](double v) { return std::isfinite(v) && std::abs(v) < 89.0; }, "within (-89, 89)");
  camera.pitch_rad = pitch_deg * M_PI / 180.0;
  camera.x_offset_m = checkedParam(
      pnh, "camera_x_offset", defaults.x_offset_m, [](double v) { return std::isfinite(v); },
      "finite");
  return camera;
}

}  // namespace follow_bot
