// Camera frames for the node tests, stamped and framed as the simulator publishes them.
#pragma once

#include <cv_bridge/cv_bridge.h>
#include <ros/time.h>
#include <sensor_msgs/Image.h>
#include <std_msgs/Header.h>

#include <vector>

#include <opencv2/core.hpp>

namespace follow_bot::test {

inline sensor_msgs::Image bgrFrame(const cv::Mat& bgr, const ros::Time& stamp) {
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = "camera_rgb_optical_frame";
  return *cv_bridge::CvImage(header, "bgr8", bgr).toImageMsg();
}

// Broken copies of a good bgr8 frame, one per kind of bad input a node must survive: unknown
// encodings, a wrong step, truncated data, a zero width, no pixels at all, an absurd height.
inline std::vector<sensor_msgs::Image> malformedFrames(const sensor_msgs::Image& good) {
  std::vector<sensor_msgs::Image> bad(7, good);
  bad[0].encoding = "bayer_rggb8";
  bad[1].encoding = "32FC1";
  bad[2].step = good.width * 3 - 1;
  bad[3].data.resize(good.data.size() / 2);
  bad[4].width = 0;
  bad[5].width = 0;
  bad[5].height = 0;
  bad[5].step = 0;
  bad[5].data.clear();
  bad[6].height = 0xFFFFFFFFu;
  return bad;
}

}  // namespace follow_bot::test
