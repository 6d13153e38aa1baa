// A planar parking marker (an AprilTag or a textured sign) seen in one image, and the interface
// both marker detectors implement so the parker servos on either without knowing which.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot/common.h"
#include "follow_bot_common/ground_projection.h"

namespace follow_bot {

// Marker frame: origin at the marker's centre, x to a viewer's right and y down as seen from
// the front, z into the marker (the ViSP and apriltag convention). The pose is that frame
// expressed in the camera optical frame (x right, y down, z forward), in metres.
struct MarkerObservation {
  int id = -1;  // tag id; 0 for a sign
  std::array<cv::Point2d, 4>
      corners;  // rectified pixels (OpenCV centres): TL, TR, BR, BL seen from the front
  cv::Matx33d rotation = cv::Matx33d::eye();
  cv::Vec3d translation;             // marker centre
  double reprojection_error_px = 0;  // RMS over the corners (tag) or the inliers (sign)
  double quality = 0;                // decision margin (tag) or RANSAC inlier count (sign)
};

class MarkerDetector {
 public:
  virtual ~MarkerDetector() = default;
  // The configured marker in a mono8 image, or nothing. Only the intrinsics and the lens of
  // `camera` are used: a raw frame's points are rectified (rectifyPixels) before the pose, and
  // the corners are the rectified camera's pixels.
  virtual std::optional<MarkerObservation> detect(const cv::Mat& gray,
                                                  const CameraGeometry& camera) = 0;
};

// The rectified camera's images (fx, fy, cx, cy) of patches of a raw frame through camera.lens,
// where straight edges are straight: what the marker detectors refine on. Building a patch's map
// (cv::initUndistortRectifyMap) cost as much as the tag search on it, every frame, so the map of
// a region around the frame is built once (again when the lens, the intrinsics or the frame size
// change) and each patch inside it reads its part; a patch reaching beyond it gets its own map.
class RectifiedPatches {
 public:
  // The patch of rectified pixels `patch` (which may reach beyond the frame), sampled from `raw`
  // (bilinear, the raw frame's edge pixels repeated beyond it). Needs a lens.
  cv::Mat patch(const cv::Mat& raw, const CameraGeometry& camera, const cv::Rect& patch);

 private:
  std::optional<CameraGeometry> camera_;  // whose map is kept (only intrinsics and lens count)
  cv::Size frame_size_;
  cv::Rect region_;  // rectified pixels the map covers
  cv::Mat map_, map_fraction_;
};

// Where the raw frame shows rectified pixels (the inverse of rectifyPixels, as image_geometry's
// unrectifyPoint): through K, D and R of camera.lens. Unchanged without a lens.
std::vector<cv::Point2d> unrectifyPixels(const CameraGeometry& camera,
                                         const std::vector<cv::Point2d>& rectified);

// Draws `marker` on `bgr`: its outline, its axes projected with `camera`'s intrinsics (x red,
// y green, z blue, each half the marker's width) and its id.
void drawMarker(cv::Mat& bgr, const MarkerObservation& marker, const CameraGeometry& camera);

}  // namespace follow_bot
