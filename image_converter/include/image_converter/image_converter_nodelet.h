// The ImageConverter nodelet (declared here so the thin node can own one directly).
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/Image.h>

#include "follow_bot_common/ros/checked_nodelet.h"
#include "follow_bot_common/ros/node_help.h"
#include "image_converter/overlay.h"

namespace image_converter {

// The image_converter node's --help: what it does, its topics.
follow_bot::NodeHelp imageConverterHelp();

class ImageConverterNodelet : public follow_bot::CheckedNodelet {
 public:
  ~ImageConverterNodelet() override;

 private:
  void init() override;
  void updateSubscription();
  void subscribe();
  void onImage(const sensor_msgs::ImageConstPtr& msg);
  void handleImage(const sensor_msgs::ImageConstPtr& msg);

  OverlayConfig overlay_;
  bool display_ = false;
  std::string transport_;
  std::unique_ptr<image_transport::ImageTransport> input_transport_;
  image_transport::Subscriber input_;
  image_transport::Publisher output_;
  std::mutex connection_mutex_;
};

}  // namespace image_converter
