// What every behaviour nodelet does with its camera topics before its own work.
#pragma once

#include <string>

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "follow_bot/ground_projection.h"
#include "image_converter/ros/frame_msg.h"

namespace follow_bot {

// The project's one frame acceptance (image_converter/ros/frame_msg.h) and callback guard.
using image_converter::bgrView;
using image_converter::guardedCallback;

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
