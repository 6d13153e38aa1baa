// ImageConverter: the lecture's node (ROS Lecture 10) as a lazy nodelet.
//
// Subscribes `camera/rgb/image_raw` (image_transport, queue 1), draws a red circle at the centre
// and publishes `~output` (bgr8). Input is subscribed only while `~output` has subscribers or a
// window is shown, so an idle converter costs nothing. /diagnostics "<node>: frames": every frame
// received, counted once under its outcome (follow_bot_common::FrameCounts).
#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <stdexcept>
#include <string>

#include <cv_bridge/cv_bridge.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <opencv2/highgui.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "follow_bot_common/ros/camera_input.h"
#include "follow_bot_common/ros/config_mapping.h"
#include "follow_bot_common/ros/params.h"
#include "follow_bot_common/ros/topics.h"
#include "image_converter/ImageConverterConfig.h"
#include "image_converter/image_converter_nodelet.h"
#include "image_converter/overlay.h"

namespace image_converter {

namespace {
constexpr char kWindowName[] = "image_converter";

bool displayAvailable() {
  const char* display = std::getenv("DISPLAY");
  return display != nullptr && display[0] != '\0';
}
}  // namespace

void ImageConverterNodelet::init() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();

  const ImageConverterConfig cfg =
      follow_bot_common::readConfig<ImageConverterConfig>(pnh);  // throws on bad ~params
  follow_bot_common::assignFromConfig(overlay_, cfg);
  display_ = cfg.display;
  transport_ = cfg.image_transport;
  if (display_ && !displayAvailable()) {
    NODELET_WARN(
        "~display is true but no X display is available (DISPLAY is unset); "
        "running headless, use the ~output topic instead");
    display_ = false;
  }

  input_transport_ = std::make_unique<image_transport::ImageTransport>(nh);
  image_transport::ImageTransport private_transport(pnh);
  const std::vector<std::string> transports = input_transport_->getLoadableTransports();
  // Lookup names are "<package>/<transport>", e.g. "image_transport/raw".
  const bool installed =
      std::any_of(transports.begin(), transports.end(), [this](const std::string& name) {
        return name.size() > transport_.size() &&
               name.compare(name.size() - transport_.size() - 1, std::string::npos,
                            "/" + transport_) == 0;
      });
  if (!installed) {
    throw std::invalid_argument("~image_transport '" + transport_ +
                                "' is not an installed image_transport plugin");
  }

  follow_bot_common::noteParamRead(pnh, "diagnostic_period");  // read by the Updater
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, pnh.getNamespace());
  diagnostics_->setHardwareID("none");
  diagnostics_->add("frames", this, &ImageConverterNodelet::reportFrames);
  // update() publishes at most every ~diagnostic_period; checked often so the last counts go out.
  diagnostics_timer_ =
      nh.createSteadyTimer(ros::WallDuration(0.1), [this](const ros::SteadyTimerEvent&) {
        follow_bot_common::guardedCallback("diagnostics", [this] { diagnostics_->update(); });
      });

  std::lock_guard<std::mutex> lock(connection_mutex_);
  const auto on_connection_change = [this](const image_transport::SingleSubscriberPublisher&) {
    updateSubscription();
  };
  output_ = private_transport.advertise("output", 1, on_connection_change, on_connection_change);
  if (display_) {
    cv::namedWindow(kWindowName);
    subscribe();
  }
}

ImageConverterNodelet::~ImageConverterNodelet() {
  if (display_) cv::destroyWindow(kWindowName);
}

void ImageConverterNodelet::updateSubscription() {
  std::lock_guard<std::mutex> lock(connection_mutex_);
  if (display_) return;  // the window keeps the input subscribed
  if (output_.getNumSubscribers() == 0) {
    input_.shutdown();
  } else if (!input_) {
    subscribe();
  }
}

void ImageConverterNodelet::subscribe() {
  const image_transport::TransportHints hints(transport_, ros::TransportHints(),
                                              getPrivateNodeHandle());
  // Resolved first, so that a remapping of the base name also moves <base>/compressed
  // (image_transport appends the transport's suffix to the name as given).
  input_ =
      input_transport_->subscribe(getNodeHandle().resolveName(follow_bot_common::topics::kImage), 1,
                                  &ImageConverterNodelet::onImage, this, hints);
}

void ImageConverterNodelet::onImage(const sensor_msgs::ImageConstPtr& msg) {
  // Guarded: an exception drops the frame (throttled error, counted), never the node.
  follow_bot_common::FrameOutcome outcome =
      follow_bot_common::FrameOutcome::kError;  // unless it returns
  follow_bot_common::guardedCallback("image", [&] { outcome = handleImage(msg); });
  std::lock_guard<std::mutex> lock(counts_mutex_);
  counts_.countFrame(outcome);
}

follow_bot_common::FrameOutcome ImageConverterNodelet::handleImage(
    const sensor_msgs::ImageConstPtr& msg) {
  const follow_bot_common::RawFrame raw = follow_bot_common::rawFrameOf(*msg);
  const follow_bot_common::FrameCheck check = follow_bot_common::checkFrame(raw);
  if (!check.ok()) {
    NODELET_ERROR_THROTTLE(1.0, "dropping frame on %s: %s", input_.getTopic().c_str(),
                           check.error.c_str());
    return check.outcome;
  }
  // The one copy (the overlay must not be drawn into a buffer other subscribers share).
  cv_bridge::CvImage annotated(msg->header, "bgr8",
                               follow_bot_common::frameToBgr8(raw, *check.encoding));
  drawOverlay(annotated.image, overlay_);

  if (output_.getNumSubscribers() > 0) output_.publish(annotated.toImageMsg());
  if (display_) {
    cv::imshow(kWindowName, annotated.image);
    cv::waitKey(1);
  }
  return follow_bot_common::FrameOutcome::kAccepted;
}

void ImageConverterNodelet::reportFrames(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(counts_mutex_);
  const long dropped = counts_.framesDropped();
  if (dropped > 0) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%ld frames dropped", dropped);
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "running");
  }
  for (const auto& [key, count] : counts_.frameValues()) status.add(key, count);
}

follow_bot_common::NodeHelp imageConverterHelp() {
  return {"Draws a red circle at the centre of each camera frame (the lecture's ImageConverter).",
          {{"in", follow_bot_common::topics::kImage, "sensor_msgs/Image",
            "image_transport, queue 1, subscribed only while ~output is; ~image_transport picks "
            "the transport"},
           {"out", "~output", "sensor_msgs/Image", "annotated, bgr8, the input's header"},
           {"out", "/diagnostics", "diagnostic_msgs/DiagnosticArray",
            "frames accepted and dropped by reason"}}};
}

}  // namespace image_converter

PLUGINLIB_EXPORT_CLASS(image_converter::ImageConverterNodelet, nodelet::Nodelet)
