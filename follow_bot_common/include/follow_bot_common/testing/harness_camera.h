// For the tests of every package that reason about camera geometry: the harness camera and a
// forward camera model written independently of pixelToGround, from the conventions in
// ground_projection.h. Header-only; test code only.
#pragma once

#include <cmath>

#include <opencv2/core.hpp>

#include "follow_bot_common/ground_projection.h"

namespace follow_bot_common {

inline double degrees(double deg) { return deg * 3.14159265358979323846 / 180.0; }

// The simulator's camera: 640x480 with a 60 deg horizontal field of view, 0.3 m up, 20 deg down,
// above base_link. Spelt out rather than CameraGeometry() (today the same) so that the tests'
// expected values stay those of the harness whatever the defaults become.
inline CameraGeometry harnessCamera() {
  CameraGeometry camera;
  camera.fx = camera.fy = 554.256;
  camera.cx = 320.0;
  camera.cy = 240.0;
  camera.height_m = 0.3;
  camera.pitch_rad = degrees(20.0);
  camera.x_offset_m = 0.0;
  return camera;
}

// A floor point (x forward, y left, m in base_link) as `camera` sees it: (u, v, depth along the
// optical axis); behind the camera when the depth is not positive. Lens distortion is ignored.
inline cv::Point3d projectToPixel(const CameraGeometry& camera, const cv::Point2d& ground) {
  const double p = camera.pitch_rad;
  const cv::Vec3d z_axis(std::cos(p), 0.0, -std::sin(p));
  const cv::Vec3d x_axis(0.0, -1.0, 0.0);
  const cv::Vec3d y_axis = z_axis.cross(x_axis);
  const cv::Vec3d from_camera(ground.x - camera.x_offset_m, ground.y, -camera.height_m);
  const double depth = from_camera.dot(z_axis);
  return cv::Point3d(camera.cx + camera.fx * from_camera.dot(x_axis) / depth,
                     camera.cy + camera.fy * from_camera.dot(y_axis) / depth, depth);
}

}  // namespace follow_bot_common
