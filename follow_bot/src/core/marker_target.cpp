#include "follow_bot/marker_target.h"

#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace follow_bot {

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
