// Camera input: glue between sensor_msgs/Image and the ROS-free frame checks (the one way every
// node in the project accepts a camera frame), camera_info to intrinsics, and the last-resort
// guard around every callback.
#pragma once

#include <algorithm>
#include <exception>
#include <optional>
#include <string>

#include <cv_bridge/cv_bridge.h>
#include <image_geometry/pinhole_camera_model.h>
#include <ros/console.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/distortion_models.h>
#include <sensor_msgs/image_encodings.h>
#include <boost/make_shared.hpp>

#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/image_frame.h"

namespace follow_bot {

inline RawFrame rawFrameOf(const sensor_msgs::Image& msg) {
  RawFrame frame;
  frame.width = msg.width;
  frame.height = msg.height;
  frame.encoding = msg.encoding;
  frame.big_endian = msg.is_bigendian != 0;
  frame.step = msg.step;
  frame.data = msg.data.data();
  frame.data_size = msg.data.size();
  frame.stamp_sec = msg.header.stamp.sec;
  frame.stamp_nsec = msg.header.stamp.nsec;
  return frame;
}

// The frame as BGR8 after checkFrame (a view of the message, no copy, when it is bgr8; a fresh
// image otherwise), or null for a frame that fails the checks (`check` says why). No cv_bridge
// conversion: checkFrame already holds everything toBgr8 relies on.
inline cv_bridge::CvImageConstPtr bgrView(const sensor_msgs::ImageConstPtr& msg,
                                          FrameCheck& check) {
  const RawFrame raw = rawFrameOf(*msg);
  check = checkFrame(raw);
  if (!check.ok()) return nullptr;
  // Only "bgr8" itself: cv_bridge refuses to share "8UC3" (the same layout) as bgr8.
  if (msg->encoding == sensor_msgs::image_encodings::BGR8) {
    return cv_bridge::toCvShare(*msg, msg, sensor_msgs::image_encodings::BGR8);
  }
  return boost::make_shared<cv_bridge::CvImage>(msg->header, sensor_msgs::image_encodings::BGR8,
                                                frameToBgr8(raw, *check.encoding));
}

// Runs one callback's work. An exception escaping it (cv::Exception, std::exception: a case the
// checks missed) must not end the process: it is logged, throttled per call site, and the
// message is dropped. Returns false when that happened.
template <typename Work>
bool guardedCallback(const char* what, Work&& work) {
  try {
    work();
    return true;
  } catch (const std::exception& error) {
    ROS_ERROR_THROTTLE(1.0, "%s: dropped after an unexpected error: %s", what, error.what());
  }
  return false;
}

// How many distortion coefficients a CameraInfo distortion_model takes (0: a model OpenCV's
// undistortPoints cannot apply).
inline size_t distortionSize(const std::string& model) {
  if (model == sensor_msgs::distortion_models::PLUMB_BOB) return 5;
  if (model == sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL) return 8;
  return 0;
}

inline bool sameLens(const std::optional<CameraLens>& a, const std::optional<CameraLens>& b) {
  if (!a || !b) return !a && !b;
  return a->camera_matrix == b->camera_matrix && a->distortion == b->distortion &&
         a->rectification == b->rectification;
}

// Whether `a` and `b` have the same intrinsics (the rectified camera and the lens).
inline bool sameIntrinsics(const CameraGeometry& a, const CameraGeometry& b) {
  return a.fx == b.fx && a.fy == b.fy && a.cx == b.cx && a.cy == b.cy && sameLens(a.lens, b.lens);
}

// The intrinsics side of `camera` from a CameraInfo, through image_geometry's PinholeCameraModel:
// the rectified camera from P (K when P is all zero, an uncalibrated P) and, for raw frames
// (`image_rectified` false) through a lens with distortion, the lens (K, D, R) the cores rectify
// their pixels with. Frames already rectified (image_proc's image_rect) use P alone. They are the
// intrinsics of images of the CameraInfo's width and height (intrinsicsForFrame fits them to
// other frame sizes). Returns "" on success, otherwise why the message was ignored (`camera` then
// unchanged).
inline std::string updateIntrinsics(const sensor_msgs::CameraInfo& info, bool image_rectified,
                                    CameraGeometry& camera) {
  image_geometry::PinholeCameraModel model;
  model.fromCameraInfo(info);
  const cv::Matx33d k = model.fullIntrinsicMatrix();
  const cv::Matx34d p = model.fullProjectionMatrix();
  const bool p_unset = p == cv::Matx34d::zeros();
  CameraGeometry updated = camera;
  updated.fx = p_unset ? k(0, 0) : p(0, 0);
  updated.fy = p_unset ? k(1, 1) : p(1, 1);
  updated.cx = p_unset ? k(0, 2) : p(0, 2);
  updated.cy = p_unset ? k(1, 2) : p(1, 2);
  updated.lens.reset();
  const bool distorted = std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0; });
  if (!image_rectified && distorted) {
    const size_t size = distortionSize(info.distortion_model);
    if (size == 0) {
      return "distortion_model '" + info.distortion_model +
             "' is not supported (plumb_bob, rational_polynomial), or send rectified frames";
    }
    if (info.D.size() != size) {
      return "D of a " + info.distortion_model + " lens must have " + std::to_string(size) +
             " coefficients, got " + std::to_string(info.D.size());
    }
    updated.lens = CameraLens{k, info.D, model.rotationMatrix()};
  }
  const std::string error = validate(updated);
  if (!error.empty()) return error;
  camera = updated;
  return "";
}

}  // namespace follow_bot
