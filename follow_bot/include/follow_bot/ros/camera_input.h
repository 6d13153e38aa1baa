// What every behaviour nodelet does with its camera topics before its own work.
#pragma once

#include <string>

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "follow_bot/ground_projection.h"
#include "image_converter/ros/frame_msg.h"

namespace follow_bot {

// The frame as BGR8 (a view of the message, no copy, when it is bgr8), or null with `error` set
// for a frame that fails the checks or cannot be converted.
inline cv_bridge::CvImageConstPtr bgrView(const sensor_msgs::ImageConstPtr& msg,
                                          std::string& error) {
  const image_converter::FrameCheck check =
      image_converter::checkFrame(image_converter::rawFrameOf(*msg));
  if (!check.ok()) {
    error = check.error;
    return nullptr;
  }
  try {
    return cv_bridge::toCvShare(msg, "bgr8");
  } catch (const cv_bridge::Exception& exception) {
    error = exception.what();
    return nullptr;
  }
}

// Copies CameraInfo's K into `camera` when it is usable. Returns "" on success, otherwise why
// the message was ignored (`camera` then unchanged). `changed` tells whether the intrinsics
// differ from before.
inline std::string updateIntrinsics(const sensor_msgs::CameraInfo& info, CameraGeometry& camera,
                                    bool& changed) {
  CameraGeometry updated = camera;
  updated.fx = info.K[0];
  updated.fy = info.K[4];
  updated.cx = info.K[2];
  updated.cy = info.K[5];
  const std::string error = validate(updated);
  if (!error.empty()) return error;
  changed = updated.fx != camera.fx || updated.fy != camera.fy || updated.cx != camera.cx ||
            updated.cy != camera.cy;
  camera = updated;
  return "";
}

}  // namespace follow_bot
