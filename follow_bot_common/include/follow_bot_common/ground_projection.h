// Maps image pixels to points on a flat floor, for a camera fixed on the robot base.
//
// Frames (REP-103): base_link has x forward, y left, z up, with the floor at z = 0. The camera's
// optical centre sits at (x_offset_m, 0, height_m); its optical axis is (cos p, 0, -sin p) for a
// pitch p (positive looks down), image right is the robot's right (0, -1, 0) and image down is
// their cross product. These match the harness simulator's camera.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "follow_bot_common/CameraDefaults.h"

namespace follow_bot_common {

// The lens between the scene and a raw (unrectified) image, CameraInfo's K, D and R: what maps a
// raw pixel to the rectified camera of CameraGeometry (image_geometry's rectifyPoint).
struct CameraLens {
  cv::Matx33d camera_matrix;                       // K of the raw image
  std::vector<double> distortion;                  // D in OpenCV's order: 4, 5, 8, 12 or 14
  cv::Matx33d rectification = cv::Matx33d::eye();  // R
};

// Defaults are the harness camera: 640x480, 60 deg horizontal field of view, 0.3 m up, 20 deg down.
struct CameraGeometry {
  // Intrinsics of the rectified camera in pixels, CameraInfo P = [fx 0 cx 0; 0 fy cy 0; 0 0 1 0]
  // (= K for a lens without distortion): what every pixel-to-ray computation uses.
  double fx = 554.256;
  double fy = 554.256;
  double cx = 320.0;
  double cy = 240.0;
  // The mounting: defaults from cfg/Camera.cfg (the ~params that set it without tf).
  double height_m = CameraDefaults::camera_height;  // optical centre above the floor
  double pitch_rad =                                // positive tilts the axis down
      CameraDefaults::camera_pitch_deg * 3.14159265358979323846 / 180.0;
  double x_offset_m = CameraDefaults::camera_x_offset;  // optical centre forward of base_link
  // Frames come through this lens (image_raw of a distorting camera): pixels are rectified with
  // rectifyPixels before any geometry. None: the frames are rectified (or the lens is a pinhole).
  std::optional<CameraLens> lens;
};

// Empty when the geometry is usable, otherwise a message naming the first bad field.
std::string validate(const CameraGeometry& camera);

// Whether `a` and `b` have the same intrinsics (the rectified camera and the lens, if any); the
// mounting is not compared.
bool sameIntrinsics(const CameraGeometry& a, const CameraGeometry& b);

// `camera` with the intrinsics it has for images of `calibrated` size (CameraInfo width, height)
// made those of frames of `frame` size: the rectified camera's fx, fy, cx, cy and the lens's K
// scaled by frame / calibrated, as image_geometry does for binning (REP 104), for a binning
// camera or a resized stream. Unchanged when the sizes are equal or `calibrated` is unknown
// (empty). Empty when `frame` is not `calibrated` resized by one factor (another aspect ratio).
std::optional<CameraGeometry> intrinsicsForFrame(const CameraGeometry& camera,
                                                 const cv::Size& calibrated, const cv::Size& frame);

// Raw image pixels (column, row) moved to where the rectified camera (fx, fy, cx, cy) sees the
// same rays: cv::undistortPoints with K, D, R and P, as image_geometry's rectifyPoint, but in
// double precision and iterated to convergence (strong barrel lenses need more than OpenCV's
// default 5 iterations near the corners). Unchanged without a lens.
std::vector<cv::Point2d> rectifyPixels(const CameraGeometry& camera,
                                       const std::vector<cv::Point2d>& raw);
std::vector<cv::Point2f> rectifyPixels(const CameraGeometry& camera,
                                       const std::vector<cv::Point2f>& raw);
cv::Point2d rectifyPixel(const CameraGeometry& camera, const cv::Point2d& raw);

// The floor point (x forward, y left, metres in base_link) seen at pixel (u, v) = (column, row),
// pixel centres at integer coordinates as in cv::moments. Empty for pixels at or above the
// horizon (their ray never meets the floor) and for non-finite input.
std::optional<cv::Point2d> pixelToGround(const CameraGeometry& camera, double u, double v);

}  // namespace follow_bot_common
