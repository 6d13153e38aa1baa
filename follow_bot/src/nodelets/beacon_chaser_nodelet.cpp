// Beacon chaser: Lab 5's "follow green, stop at red" and the lecture's "approach the dumpster and
// stop 1 m in front of it", as one nodelet. One camera frame in, one Twist out.
//
// Thin wiring around ColourBlobDetector and BeaconController; CommandOutput adds limits, the
// frame watchdog and the final stop.
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/CameraInfo.h>
#include <std_msgs/Bool.h>
#include <opencv2/imgproc.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "follow_bot/BeaconDetections.h"
#include "follow_bot/beacon_controller.h"
#include "follow_bot/colour_blobs.h"
#include "follow_bot/ros/camera_input.h"
#include "follow_bot/ros/command_output.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot/ros/params.h"

namespace follow_bot {

namespace {

template <typename T>
T param(const ros::NodeHandle& pnh, const std::string& name, T fallback) {
  T value = fallback;
  pnh.param(name, value, fallback);
  return value;
}

void throwIfError(const std::string& error) {
  if (!error.empty()) throw std::invalid_argument(error);
}

// Every ~param, validated by the core's own checks; throws std::invalid_argument.
std::pair<ColourBlobConfig, BeaconControllerConfig> readConfigs(const ros::NodeHandle& pnh) {
  ColourBlobConfig detector;
  const int sensitivity = param(pnh, "sensitivity", 15);
  const int s_min = param(pnh, "s_min", 100);
  // Low: a dark-green dumpster in dim light has V ~ 30; grey floor is rejected by s_min anyway.
  const int v_min = param(pnh, "v_min", 20);
  for (ColourSpec& colour : detector.colours) {
    colour.sensitivity = sensitivity;
    colour.s_min = s_min;
    colour.v_min = v_min;
  }
  detector.min_area = param(pnh, "min_area", detector.min_area);
  throwIfError(validate(detector));

  BeaconControllerConfig controller;
  const std::string mode = param<std::string>(pnh, "mode", toString(controller.mode));
  const std::optional<BeaconMode> parsed_mode = parseBeaconMode(mode);
  if (!parsed_mode) {
    throw std::invalid_argument("~mode must be 'follow_green_stop_red' or 'approach', got '" +
                                mode + "'");
  }
  controller.mode = *parsed_mode;
  controller.target_colour = param(pnh, "target_colour", controller.target_colour);
  if (!parseColourName(controller.target_colour)) {  // checked in every mode: a typo is a typo
    throw std::invalid_argument("~target_colour must be red, green or blue, got '" +
                                controller.target_colour + "'");
  }
  const std::string shape = param<std::string>(pnh, "target_shape", "box");
  const std::optional<BeaconShape> parsed_shape = parseBeaconShape(shape);
  if (!parsed_shape) {
    throw std::invalid_argument("~target_shape must be 'box' or 'sphere', got '" + shape + "'");
  }
  controller.target.shape = *parsed_shape;
  controller.target.size_m = param(pnh, "target_size", controller.target.size_m);
  controller.stop_distance = param(pnh, "stop_distance", controller.stop_distance);
  controller.max_speed = param(pnh, "max_speed", controller.max_speed);
  controller.approach_speed = param(pnh, "approach_speed", controller.approach_speed);
  controller.search_rate = param(pnh, "search_rate", controller.search_rate);
  controller.close_area = param(pnh, "close_area", controller.close_area);
  controller.camera.height_m = param(pnh, "camera_height", controller.camera.height_m);
  controller.camera.pitch_rad = param(pnh, "camera_pitch_deg", 0.0) * M_PI / 180.0;
  controller.camera.x_offset_m = param(pnh, "camera_x_offset", controller.camera.x_offset_m);
  throwIfError(validate(controller));
  throwIfError(checkColoursDetected(controller, detector));
  return {detector, controller};
}

}  // namespace

class BeaconChaserNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    const auto [detector, controller] = readConfigs(pnh);  // throws on bad ~params
    detector_ = std::make_unique<ColourBlobDetector>(detector);
    controller_config_ = controller;
    controller_ = std::make_unique<BeaconController>(controller);
    output_ = std::make_unique<CommandOutput>(nh, pnh);

    detections_pub_ = pnh.advertise<BeaconDetections>("detections", 1);
    for (const ColourSpec& colour : detector.colours) {  // Lab 5 step 3: one flag per colour
      found_pubs_.push_back(pnh.advertise<std_msgs::Bool>(colour.name + "_found", 1));
    }
    image_transport::ImageTransport private_transport(pnh);
    debug_pub_ = private_transport.advertise("debug_image", 1);
    camera_info_sub_ = nh.subscribe("camera_info", 1, &BeaconChaserNodelet::onCameraInfo, this);
    image_transport::ImageTransport transport(nh);
    image_sub_ = transport.subscribe("image", 1, &BeaconChaserNodelet::onImage, this);
  }

  // Ranges need the intrinsics; the controller is rebuilt when they change.
  void onCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    std::lock_guard<std::mutex> lock(mutex_);
    bool changed = false;
    const std::string error = updateIntrinsics(*info, controller_config_.camera, changed);
    if (!error.empty()) {
      NODELET_ERROR_THROTTLE(5.0, "ignoring camera_info: %s", error.c_str());
      return;
    }
    if (changed || !has_intrinsics_) {
      controller_ = std::make_unique<BeaconController>(controller_config_);
      has_intrinsics_ = true;
    }
  }

  void onImage(const sensor_msgs::ImageConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string error;
    const cv_bridge::CvImageConstPtr frame = bgrView(msg, error);
    if (!frame) {
      NODELET_ERROR_THROTTLE(1.0, "dropping frame: %s", error.c_str());
      return;
    }
    output_->frameArrived();
    const BlobResult blobs = detector_->detect(frame->image);
    const ros::Time stamp = msg->header.stamp.isZero() ? ros::Time::now() : msg->header.stamp;
    Twist2D desired;
    if (controller_config_.mode == BeaconMode::kApproach && !has_intrinsics_) {
      NODELET_WARN_THROTTLE(2.0, "approach needs camera_info on %s for ranges: holding still",
                            camera_info_sub_.getTopic().c_str());
    } else {
      desired = controller_->update(blobs, stamp.toSec());
    }
    const Twist2D command = output_->send(desired, stamp);
    publishDetections(*msg, blobs, command);
    if (debug_pub_.getNumSubscribers() > 0) publishDebug(*frame, blobs);
  }

  void publishDetections(const sensor_msgs::Image& msg, const BlobResult& blobs,
                         const Twist2D& command) {
    for (std::size_t i = 0; i < blobs.colours.size() && i < found_pubs_.size(); ++i) {
      std_msgs::Bool found;
      found.data = blobs.colours[i].found;
      found_pubs_[i].publish(found);
    }
    if (detections_pub_.getNumSubscribers() == 0) return;
    BeaconDetections out;
    out.header = msg.header;
    for (const ColourBlob& blob : blobs.colours) {
      BeaconDetection detection;
      detection.colour = blob.name;
      detection.found = blob.found;
      detection.area = blob.area;
      detection.centroid_x = blob.centroid.x;
      detection.centroid_y = blob.centroid.y;
      detection.radius = blob.circle_radius;
      detection.range = std::numeric_limits<float>::quiet_NaN();
      if (blob.name == controller_config_.target_colour && controller_->lastRange()) {
        detection.range = *controller_->lastRange();
      }
      out.detections.push_back(detection);
    }
    out.state = toString(controller_->state());
    out.linear = command.linear;
    out.angular = command.angular;
    detections_pub_.publish(out);
  }

  void publishDebug(const cv_bridge::CvImage& frame, const BlobResult& blobs) {
    cv_bridge::CvImage debug(frame.header, "bgr8", frame.image.clone());
    for (const ColourBlob& blob : blobs.colours) {
      if (!blob.found) continue;
      cv::drawContours(debug.image, std::vector<std::vector<cv::Point>>{blob.contour}, 0,
                       cv::Scalar(255, 255, 255), 2);
      cv::circle(debug.image, blob.circle_centre, static_cast<int>(blob.circle_radius),
                 cv::Scalar(0, 255, 255), 1);
      cv::putText(debug.image, blob.name, blob.bounding_box.tl() - cv::Point(0, 5),
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(255, 255, 255), 2);
    }
    debug_pub_.publish(debug.toImageMsg());
  }

  std::mutex mutex_;
  std::unique_ptr<ColourBlobDetector> detector_;
  BeaconControllerConfig controller_config_;
  std::unique_ptr<BeaconController> controller_;
  bool has_intrinsics_ = false;
  std::unique_ptr<CommandOutput> output_;
  ros::Publisher detections_pub_;
  std::vector<ros::Publisher> found_pubs_;
  image_transport::Publisher debug_pub_;
  ros::Subscriber camera_info_sub_;
  image_transport::Subscriber image_sub_;
};

std::unique_ptr<nodelet::Nodelet> makeBeaconChaserNodelet() {
  return std::make_unique<BeaconChaserNodelet>();
}

}  // namespace follow_bot

PLUGINLIB_EXPORT_CLASS(follow_bot::BeaconChaserNodelet, nodelet::Nodelet)
