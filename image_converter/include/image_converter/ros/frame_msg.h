// Glue between sensor_msgs/Image and the ROS-free frame checks.
#pragma once

#include <sensor_msgs/Image.h>

#include "image_converter/image_frame.h"

namespace image_converter {

inline RawFrame rawFrameOf(const sensor_msgs::Image& msg) {
  RawFrame frame;
  frame.width = msg.width;
  frame.height = msg.height;
  frame.encoding = msg.encoding;
  frame.step = msg.step;
  frame.data = msg.data.data();
  frame.data_size = msg.data.size();
  return frame;
}

}  // namespace image_converter
