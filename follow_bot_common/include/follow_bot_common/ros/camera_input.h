// Camera input: glue between sensor_msgs/Image and the ROS-free frame checks (the one way every
// node in the project accepts a camera frame), and the last-resort guard around every callback.
// camera_info to intrinsics: intrinsics_source.h.
#pragma once

#include <exception>
#include <string>

#include <cv_bridge/cv_bridge.h>
#include <ros/console.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>
#include <boost/make_shared.hpp>

#include "follow_bot_common/image_frame.h"

namespace follow_bot_common {

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

}  // namespace follow_bot_common
