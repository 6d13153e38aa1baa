// Follower: the lecture's Follow-Bot as a nodelet. One camera frame in, one Twist out.
//
// Thin wiring around LineDetector (band-only HSV threshold + moments) and LineController
// (lecture law or PD with line search); CommandOutput adds limits, the frame watchdog and the
// final stop. Thresholds and gains are ~params, also live through dynamic_reconfigure.
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <cv_bridge/cv_bridge.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "follow_bot/FollowerConfig.h"
#include "follow_bot/LineStatus.h"
#include "follow_bot/line_controller.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/ros/command_output.h"
#include "follow_bot/ros/nodelets.h"
#include "image_converter/ros/frame_msg.h"

namespace follow_bot {

namespace {

// Everything dynamic_reconfigure can change, as core configurations. Throws
// std::invalid_argument naming the first bad value.
std::pair<LineDetectorConfig, LineControllerConfig> coreConfigs(const FollowerConfig& cfg) {
  // dynamic_reconfigure clamps live updates, but ~params read at start-up are not clamped.
  FollowerConfig clamped = cfg;
  clamped.__clamp__();
  for (const auto& param : FollowerConfig::__getParamDescriptions__()) {
    uint32_t changed = 0;  // every parameter has level 1: non-zero when clamping changed it
    param->calcLevel(changed, cfg, clamped);
    if (changed != 0) {
      throw std::invalid_argument("~" + param->name + " is outside its range (" +
                                  param->description + "; ranges in README.md)");
    }
  }
  LineDetectorConfig detector;
  detector.lower = {cfg.h_min, cfg.s_min, cfg.v_min};
  detector.upper = {cfg.h_max, cfg.s_max, cfg.v_max};
  detector.band = {cfg.band_top_fraction, cfg.band_rows};
  detector.look_ahead_enabled = cfg.look_ahead;
  detector.look_ahead = {cfg.look_ahead_top_fraction, cfg.band_rows};
  detector.min_pixels = cfg.min_pixels;

  LineControllerConfig controller;
  const std::optional<ControlMode> mode = parseControlMode(cfg.mode);
  if (!mode) throw std::invalid_argument("~mode must be 'lecture' or 'pd', got '" + cfg.mode + "'");
  controller.mode = *mode;
  controller.kp = cfg.kp;
  controller.kd = cfg.kd;
  controller.max_linear = cfg.max_linear;
  controller.min_linear = cfg.min_linear;
  controller.taper = cfg.taper;
  controller.max_angular = cfg.max_angular;
  controller.look_ahead_weight = cfg.look_ahead_weight;
  controller.search_rate = cfg.search_rate;

  for (const std::string& error : {validate(detector), validate(controller)}) {
    if (!error.empty()) throw std::invalid_argument(error);
  }
  return {detector, controller};
}

}  // namespace

class FollowerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();

    FollowerConfig cfg = FollowerConfig::__getDefault__();
    cfg.__fromServer__(pnh);
    const auto [detector, controller] = coreConfigs(cfg);  // throws on bad ~params
    detector_ = std::make_unique<LineDetector>(detector);
    controller_ = std::make_unique<LineController>(controller);
    output_ = std::make_unique<CommandOutput>(nh, pnh);

    reconfigure_ = std::make_unique<dynamic_reconfigure::Server<FollowerConfig>>(mutex_, pnh);
    reconfigure_->setCallback([this](FollowerConfig& config, uint32_t) { reconfigure(config); });

    status_pub_ = pnh.advertise<LineStatus>("line", 1);
    image_transport::ImageTransport private_transport(pnh);
    debug_pub_ = private_transport.advertise("debug_image", 1);
    image_transport::ImageTransport transport(nh);
    image_sub_ = transport.subscribe("image", 1, &FollowerNodelet::onImage, this);
  }

  // Called with mutex_ held by the dynamic_reconfigure server.
  void reconfigure(const FollowerConfig& config) {
    try {
      const auto [detector, controller] = coreConfigs(config);
      detector_ = std::make_unique<LineDetector>(detector);
      if (controller.mode != controller_->config().mode) controller_->reset();
      controller_ = std::make_unique<LineController>(controller);
    } catch (const std::invalid_argument& error) {
      NODELET_ERROR("rejected reconfiguration, keeping the previous settings: %s", error.what());
    }
  }

  void onImage(const sensor_msgs::ImageConstPtr& msg) {
    std::lock_guard<boost::recursive_mutex> lock(mutex_);
    const image_converter::FrameCheck check =
        image_converter::checkFrame(image_converter::rawFrameOf(*msg));
    if (!check.ok()) {
      NODELET_ERROR_THROTTLE(1.0, "dropping frame: %s", check.error.c_str());
      return;
    }
    cv_bridge::CvImageConstPtr frame;
    try {
      frame = cv_bridge::toCvShare(msg, "bgr8");  // no copy when the camera sends bgr8
    } catch (const cv_bridge::Exception& error) {
      NODELET_ERROR_THROTTLE(1.0, "dropping frame: %s", error.what());
      return;
    }
    // Only usable frames feed the watchdog: a stream of garbage must stop the robot too.
    output_->frameArrived();
    const LineStatus status = follow(*frame, *msg);
    if (status_pub_.getNumSubscribers() > 0) status_pub_.publish(status);
  }

  LineStatus follow(const cv_bridge::CvImage& frame, const sensor_msgs::Image& msg) {
    const LineMeasurement seen = detector_->detect(frame.image);
    const ros::Time stamp = msg.header.stamp.isZero() ? ros::Time::now() : msg.header.stamp;
    const Twist2D command = output_->send(controller_->update(seen, stamp.toSec()), stamp);
    if (!seen.band.found) {
      NODELET_WARN_THROTTLE(2.0, "no line in the band (%s)", toString(controller_->state()));
    }
    if (debug_pub_.getNumSubscribers() > 0) {
      cv_bridge::CvImage debug(msg.header, "bgr8", frame.image.clone());
      detector_->drawDebug(debug.image, seen);
      debug_pub_.publish(debug.toImageMsg());
    }
    LineStatus out;
    out.header = msg.header;
    out.found = seen.band.found;
    out.centroid_x = seen.band.centroid_x;
    out.centroid_y = seen.band.centroid_y;
    out.error = seen.band.error_normalised;
    out.confidence = seen.band.confidence;
    out.pixel_count = seen.band.pixel_count;
    out.state = toString(controller_->state());
    out.linear = command.linear;
    out.angular = command.angular;
    return out;
  }

  boost::recursive_mutex mutex_;  // the type dynamic_reconfigure::Server shares
  std::unique_ptr<LineDetector> detector_;
  std::unique_ptr<LineController> controller_;
  std::unique_ptr<CommandOutput> output_;
  std::unique_ptr<dynamic_reconfigure::Server<FollowerConfig>> reconfigure_;
  ros::Publisher status_pub_;
  image_transport::Publisher debug_pub_;
  image_transport::Subscriber image_sub_;
};

std::unique_ptr<nodelet::Nodelet> makeFollowerNodelet() {
  return std::make_unique<FollowerNodelet>();
}

}  // namespace follow_bot

PLUGINLIB_EXPORT_CLASS(follow_bot::FollowerNodelet, nodelet::Nodelet)
