// Follower: the lecture's Follow-Bot as a nodelet. One camera frame in, one status out; a Twist
// while it follows or searches, silence once it has given up.
//
// Thin wiring around LineDetector (band-only HSV threshold + moments) and a SteeringLaw (the
// lecture's, pd or path; makeSteeringLaw); CommandOutput adds limits, the frame watchdog and the
// final stop. Thresholds and gains are ~params, also live through dynamic_reconfigure.
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <cv_bridge/cv_bridge.h>
#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/CameraInfo.h>
#include <pluginlib/class_list_macros.hpp>

#include "follow_bot/FollowerConfig.h"
#include "follow_bot/LineStatus.h"
#include "follow_bot/line_detector.h"
#include "follow_bot/ros/camera_input.h"
#include "follow_bot/ros/command_output.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot/ros/params.h"
#include "follow_bot/steering_law.h"
#include "image_converter/ros/checked_nodelet.h"

namespace follow_bot {

namespace {

// Everything dynamic_reconfigure can change, as core configurations.
struct Settings {
  LineDetectorConfig detector;
  SteeringConfig steering;
};

// Throws std::invalid_argument naming the first bad value. Ranges are the .cfg's: readConfig
// checks them at start-up, the dynamic_reconfigure server clamps live updates to them.
Settings coreSettings(const FollowerConfig& cfg) {
  Settings settings;
  LineDetectorConfig& detector = settings.detector;
  detector.lower = {cfg.h_min, cfg.s_min, cfg.v_min};
  detector.upper = {cfg.h_max, cfg.s_max, cfg.v_max};
  detector.band = {cfg.band_top_fraction, cfg.band_rows};
  detector.look_ahead_enabled = cfg.look_ahead;
  detector.look_ahead = {cfg.look_ahead_top_fraction, cfg.band_rows};
  detector.min_pixels = cfg.min_pixels;

  SteeringConfig& steering = settings.steering;
  const std::optional<SteeringMode> mode = parseSteeringMode(cfg.mode);
  if (!mode) {
    throw std::invalid_argument("~mode must be 'lecture', 'pd' or 'path', got '" + cfg.mode + "'");
  }
  steering.mode = *mode;
  steering.max_linear = cfg.max_linear;
  steering.min_linear = cfg.min_linear;
  steering.max_angular = cfg.max_angular;
  steering.pd.kp = cfg.kp;
  steering.pd.kd = cfg.kd;
  steering.pd.taper = cfg.taper;
  steering.pd.look_ahead_weight = cfg.look_ahead_weight;
  steering.search.search_rate = cfg.search_rate;
  steering.path.heading_gain = cfg.heading_gain;
  steering.path.lateral_gain = cfg.lateral_gain;

  for (const std::string& error : {validate(detector), validate(steering)}) {
    if (!error.empty()) throw std::invalid_argument(error);
  }
  return settings;
}

}  // namespace

class FollowerNodelet : public image_converter::CheckedNodelet {
 private:
  void init() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();

    applied_config_ = readConfig<FollowerConfig>(pnh);  // throws on bad ~params
    apply(coreSettings(applied_config_));
    camera_ = readCameraMounting(pnh);
    output_ = std::make_unique<CommandOutput>(nh, pnh);
    camera_info_sub_ = nh.subscribe("camera_info", 1, &FollowerNodelet::onCameraInfo, this);
    use_odom_ = param(pnh, "use_odom", false);
    if (use_odom_) odom_sub_ = nh.subscribe("odom", 1, &FollowerNodelet::onOdometry, this);

    reconfigure_ = std::make_unique<dynamic_reconfigure::Server<FollowerConfig>>(mutex_, pnh);
    reconfigure_->setCallback([this](FollowerConfig& config, uint32_t) { reconfigure(config); });

    status_pub_ = pnh.advertise<LineStatus>("line", 1);
    image_transport::ImageTransport private_transport(pnh);
    debug_pub_ = private_transport.advertise("debug_image", 1);
    image_transport::ImageTransport transport(nh);
    image_sub_ = transport.subscribe("image", 1, &FollowerNodelet::onImage, this);
  }

  // Called with mutex_ held by the dynamic_reconfigure server. A combination the core rejects
  // changes nothing, and the server then reports the settings still in force.
  void reconfigure(FollowerConfig& config) {
    const std::string error = applyOrKeep(
        config, applied_config_, [this](const FollowerConfig& c) { apply(coreSettings(c)); });
    if (!error.empty()) {
      NODELET_WARN("rejected reconfiguration, keeping the previous settings: %s", error.c_str());
    }
  }

  // New settings start with fresh controller state (a new law must not inherit the old one's).
  void apply(const Settings& settings) {
    settings_ = settings;
    detector_ = std::make_unique<LineDetector>(settings.detector);
    // Until camera_info arrives path mode steers with pd.
    law_ =
        makeSteeringLaw(settings.steering, has_intrinsics_ ? std::optional(camera_) : std::nullopt);
  }

  // Every callback runs guarded: an exception drops the message, never the node.
  void onCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    guardedCallback("camera_info", [&] { handleCameraInfo(info); });
  }

  void handleCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    std::lock_guard<boost::recursive_mutex> lock(mutex_);
    bool changed = false;
    const std::string error = updateIntrinsics(*info, camera_, changed);
    if (!error.empty()) {
      NODELET_ERROR_THROTTLE(5.0, "ignoring camera_info: %s", error.c_str());
      return;
    }
    if (changed || !has_intrinsics_) {
      has_intrinsics_ = true;
      apply(settings_);
    }
  }

  // The base's measured motion: better than the commands for path mode's memory whenever the
  // base lags or slips.
  void onOdometry(const nav_msgs::OdometryConstPtr& odom) {
    guardedCallback("odom", [&] { handleOdometry(odom); });
  }

  void handleOdometry(const nav_msgs::OdometryConstPtr& odom) {
    std::lock_guard<boost::recursive_mutex> lock(mutex_);
    odom_twist_ = Twist2D{odom->twist.twist.linear.x, odom->twist.twist.angular.z};
    has_odom_ = true;
  }

  Twist2D steer(const LineMeasurement& seen, double stamp) {
    if (law_->mode() == SteeringMode::kPath && use_odom_ && !has_odom_) {
      NODELET_WARN_THROTTLE(5.0, "~use_odom: no odometry on %s yet, using the commands sent",
                            odom_sub_.getTopic().c_str());
    }
    if (law_->mode() != settings_.steering.mode) {
      NODELET_WARN_THROTTLE(5.0, "path mode: no valid camera_info on %s yet, steering with pd",
                            camera_info_sub_.getTopic().c_str());
    }
    return law_->step({seen, stamp, has_odom_ ? odom_twist_ : last_command_});
  }

  LineState state() const { return law_->state(); }

  void onImage(const sensor_msgs::ImageConstPtr& msg) {
    guardedCallback("image", [&] { handleImage(msg); });
  }

  void handleImage(const sensor_msgs::ImageConstPtr& msg) {
    std::lock_guard<boost::recursive_mutex> lock(mutex_);
    std::string error;
    const cv_bridge::CvImageConstPtr frame = bgrView(msg, error);
    if (!frame) {
      NODELET_ERROR_THROTTLE(1.0, "dropping frame: %s", error.c_str());
      output_->frameDropped(error);
      return;
    }
    // Only usable frames feed the watchdog: a stream of garbage must stop the robot too.
    output_->frameArrived();
    const LineStatus status = follow(*frame, *msg);
    if (status_pub_.getNumSubscribers() > 0) status_pub_.publish(status);
  }

  LineStatus follow(const cv_bridge::CvImage& frame, const sensor_msgs::Image& msg) {
    const LineMeasurement seen = detector_->detect(frame.image);
    const Twist2D desired = steer(seen, CommandOutput::frameTime(msg.header).toSec());
    // Idle once it has given up: any sighting makes it active again.
    const Twist2D command =
        output_->send(msg.header, desired, state() != LineState::kGaveUp, toString(state()));
    last_command_ = command;
    if (!seen.band.found) NODELET_WARN_THROTTLE(2.0, "no line in the band (%s)", toString(state()));
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
    out.state = toString(state());
    out.linear = command.linear;
    out.angular = command.angular;
    return out;
  }

  boost::recursive_mutex mutex_;  // the type dynamic_reconfigure::Server shares
  std::unique_ptr<LineDetector> detector_;
  std::unique_ptr<SteeringLaw> law_;
  Settings settings_;
  FollowerConfig applied_config_;  // the dynamic_reconfigure settings in force
  CameraGeometry camera_;
  bool has_intrinsics_ = false;
  Twist2D last_command_;  // what the robot was told to do since the previous frame
  ros::Subscriber camera_info_sub_;
  bool use_odom_ = false;
  bool has_odom_ = false;
  Twist2D odom_twist_;
  ros::Subscriber odom_sub_;
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
