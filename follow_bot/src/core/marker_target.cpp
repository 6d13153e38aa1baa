#include "follow_bot/marker_target.h"

#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace follow_bot {

namespace {

// The rectified camera's map of the rectified pixels `region` into the raw frame, in the
// fixed-point form cv::remap reads fastest.
void rectifyMap(const CameraGeometry& camera, const cv::Rect& region, cv::Mat& map,
                cv::Mat& map_fraction) {
  const CameraLens& lens = camera.lens.value();
  const cv::Matx33d region_camera(camera.fx, 0.0, camera.cx - region.x, 0.0, camera.fy,
                                  camera.cy - region.y, 0.0, 0.0, 1.0);
  cv::initUndistortRectifyMap(lens.camera_matrix, lens.distortion, lens.rectification,
                              region_camera, region.size(), CV_16SC2, map, map_fraction);
}

}  // namespace

cv::Mat RectifiedPatches::patch(const cv::Mat& raw, const CameraGeometry& camera,
                                const cv::Rect& patch) {
  if (!camera_ || !sameIntrinsics(*camera_, camera) || frame_size_ != raw.size()) {
    // The frame and half of it again each way: the patches of markers partly out of view too.
    region_ = cv::Rect(-raw.cols / 2, -raw.rows / 2, 2 * raw.cols, 2 * raw.rows);
    rectifyMap(camera, region_, map_, map_fraction_);
    camera_ = camera;
    frame_size_ = raw.size();
  }
  cv::Mat map, map_fraction, rectified;
  if ((patch & region_) == patch) {
    const cv::Rect inside = patch - region_.tl();
    map = map_(inside);
    map_fraction = map_fraction_(inside);
  } else {
    rectifyMap(camera, patch, map, map_fraction);
  }
  cv::remap(raw, rectified, map, map_fraction, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return rectified;
}

std::vector<cv::Point2d> unrectifyPixels(const CameraGeometry& camera,
                                         const std::vector<cv::Point2d>& rectified) {
  if (!camera.lens || rectified.empty()) return rectified;
  const CameraLens& lens = *camera.lens;
  // Rectified pixel -> ray of the rectified camera -> the raw camera's ray (R maps raw rays to
  // rectified ones) -> through K and D.
  std::vector<cv::Point3d> rays;
  rays.reserve(rectified.size());
  const cv::Matx33d to_raw = lens.rectification.t();
  for (const cv::Point2d& p : rectified) {
    const cv::Vec3d ray =
        to_raw * cv::Vec3d((p.x - camera.cx) / camera.fx, (p.y - camera.cy) / camera.fy, 1.0);
    rays.emplace_back(ray[0], ray[1], ray[2]);
  }
  std::vector<cv::Point2d> raw;
  cv::projectPoints(rays, cv::Vec3d(), cv::Vec3d(), lens.camera_matrix, lens.distortion, raw);
  return raw;
}

void drawMarker(cv::Mat& bgr, const MarkerObservation& marker, const CameraGeometry& camera) {
  std::vector<cv::Point> outline;
  for (const cv::Point2d& corner : marker.corners) outline.emplace_back(corner);
  cv::polylines(bgr, outline, true, cv::Scalar(0, 255, 255), 2);
  const double half = cv::norm(marker.corners[1] - marker.corners[0]) > 0
                          ? 0.5 * cv::norm(marker.translation) *
                                cv::norm(marker.corners[1] - marker.corners[0]) / camera.fx
                          : 0.1;
  const std::vector<cv::Point3d> axes = {{0, 0, 0}, {half, 0, 0}, {0, half, 0}, {0, 0, half}};
  cv::Vec3d rvec;
  cv::Rodrigues(marker.rotation, rvec);
  const cv::Matx33d k(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  std::vector<cv::Point2d> projected;
  cv::projectPoints(axes, rvec, marker.translation, k, cv::noArray(), projected);
  const cv::Scalar colours[] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}};
  for (int i = 0; i < 3; ++i) {
    cv::line(bgr, projected[0], projected[i + 1], colours[i], 2);
  }
  cv::putText(bgr, "id " + std::to_string(marker.id), outline[0] - cv::Point(0, 8),
              cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 255, 255), 2);
}

}  // namespace follow_bot
