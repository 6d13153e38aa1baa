// Camera frames for the node tests, stamped and framed as the simulator publishes them.
#pragma once

#include <cv_bridge/cv_bridge.h>
#include <ros/time.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>

#include <opencv2/core.hpp>

namespace follow_bot {
namespace test {

inline sensor_msgs::Image bgrFrame(const cv::Mat& bgr, const ros::Time& stamp) {
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = "camera_rgb_optical_frame";
  return *cv_bridge::CvImage(header, "bgr8", bgr).toImageMsg();
}

}  // namespace test
}  // namespace follow_bot
