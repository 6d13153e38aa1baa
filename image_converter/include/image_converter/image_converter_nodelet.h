// The ImageConverter nodelet (declared here so the thin node can own one directly).
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/Image.h>

#include "follow_bot_common/frame_counts.h"
#include "follow_bot_common/ros/checked_nodelet.h"
#include "follow_bot_common/ros/node_help.h"
#include "image_converter/overlay.h"

namespace image_converter {

// The image_converter node's --help: what it does, its topics.
follow_bot_common::NodeHelp imageConverterHelp();

class ImageConverterNodelet : public follow_bot_common::CheckedNodelet {
 public:
  ~ImageConverterNodelet() override;

 private:
  void init() override;
  void updateSubscription();
  void subscribe();
  void onImage(const sensor_msgs::ImageConstPtr& msg);
  follow_bot_common::FrameOutcome handleImage(const sensor_msgs::ImageConstPtr& msg);
  void reportFrames(diagnostic_updater::DiagnosticStatusWrapper& status);

  OverlayConfig overlay_;
  bool display_ = false;
  std::string transport_;
  std::unique_ptr<image_transport::ImageTransport> input_transport_;
  image_transport::Subscriber input_;
  image_transport::Publisher output_;
  std::mutex connection_mutex_;
  std::mutex counts_mutex_;  // frames and the diagnostics timer may run on different threads
  follow_bot_common::FrameCounts counts_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  ros::SteadyTimer diagnostics_timer_;
};

}  // namespace image_converter
