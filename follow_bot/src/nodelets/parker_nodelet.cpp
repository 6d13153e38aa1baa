// Parker: find the parking marker (an AprilTag or a textured sign) and servo the robot to park
// square in front of it. One camera frame in, one status out; a Twist until it is parked.
//
// Thin wiring around a MarkerDetector (TagDetector or SignDetector, by ~target) and
// ParkingServo; CommandOutput adds limits (reversing allowed), the frame watchdog and the final
// stop.
#include <cmath>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <sensor_msgs/CameraInfo.h>
#include <std_msgs/String.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/transform_broadcaster.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <pluginlib/class_list_macros.hpp>

#include "follow_bot/ParkerConfig.h"
#include "follow_bot/marker_target.h"
#include "follow_bot/parking_servo.h"
#include "follow_bot/ros/camera_input.h"
#include "follow_bot/ros/command_output.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot/ros/params.h"
#include "follow_bot/sign_detector.h"
#include "follow_bot/tag_detector.h"
#include "image_converter/ros/checked_nodelet.h"

namespace follow_bot {

namespace {

constexpr double kDegToRad = M_PI / 180.0;

// The core's message names its field ("family must be ..."); the user typed ~tag_family.
std::string tagError(const std::string& error) { return "~tag_" + error; }

// The marker detector `cfg.target` names; throws std::invalid_argument naming the ~param.
std::unique_ptr<MarkerDetector> makeDetector(const ParkerConfig& cfg) {
  if (cfg.target == "apriltag") {
    TagDetectorConfig config;
    config.family = cfg.tag_family;
    config.id = cfg.tag_id;
    config.size_m = cfg.tag_size;
    config.quad_decimate = cfg.quad_decimate;
    config.min_decision_margin = cfg.min_decision_margin;
    config.max_hamming = cfg.max_hamming;
    if (const std::string error = validate(config); !error.empty()) {
      throw std::invalid_argument(tagError(error));
    }
    try {
      return std::make_unique<TagDetector>(config);  // throws on an id the family lacks
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(tagError(error.what()));
    }
  }
  if (cfg.target == "sign") {
    SignDetectorConfig config;
    config.image_path = cfg.sign_image;
    config.width_m = cfg.sign_width;
    if (config.image_path.empty()) {
      throw std::invalid_argument("~sign_image must name the sign's reference image file");
    }
    try {
      return std::make_unique<SignDetector>(config);  // throws on a missing/featureless image
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(std::string("~sign_image: ") + error.what());
    }
  }
  throw std::invalid_argument("~target must be 'apriltag' or 'sign', got '" + cfg.target + "'");
}

// Ranges are the .cfg's (readConfig checked them); the one rule linking two ~params is here.
ParkingServoConfig servoConfig(const ParkerConfig& cfg, const CameraGeometry& camera) {
  ParkingServoConfig config;
  config.standoff_m = cfg.standoff;
  config.gain = cfg.gain;
  config.steer_gain = cfg.steer_gain;
  config.max_bearing_rad = cfg.max_bearing_deg * kDegToRad;
  config.backoff_m = cfg.backoff;
  config.max_linear = cfg.max_linear;
  config.max_angular = cfg.max_angular;
  config.search_rate = cfg.search_rate;
  config.lost_timeout = cfg.lost_timeout;
  config.position_tolerance = cfg.position_tolerance;
  config.lateral_tolerance = cfg.lateral_tolerance;
  config.heading_tolerance_rad = cfg.heading_tolerance_deg * kDegToRad;
  config.camera = camera;
  if (config.standoff_m - camera.x_offset_m <= 0.05) {
    std::ostringstream error;
    error << "~standoff must exceed ~camera_x_offset + 0.05 m (the marker > 5 cm in front of the "
             "camera), got "
          << config.standoff_m << " with ~camera_x_offset " << camera.x_offset_m;
    throw std::invalid_argument(error.str());
  }
  // Anything else validate() rejects is outside the .cfg's ranges: a bug, not a user error.
  if (const std::string error = validate(config); !error.empty()) {
    throw std::logic_error("parking servo: " + error);
  }
  return config;
}

}  // namespace

class ParkerNodelet : public image_converter::CheckedNodelet {
 private:
  void init() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    const ParkerConfig cfg = readConfig<ParkerConfig>(pnh);  // throws on bad ~params
    detector_ = makeDetector(cfg);
    CameraGeometry level;  // ~camera_pitch_deg defaults to 0
    level.pitch_rad = 0.0;
    camera_ = readCameraMounting(pnh, level);
    const ParkingServoConfig servo_config = servoConfig(cfg, camera_);
    servo_ = std::make_unique<ParkingServo>(servo_config);
    publish_tf_ = cfg.publish_tf;
    marker_frame_ = cfg.marker_frame;
    output_ = std::make_unique<CommandOutput>(nh, pnh, /*allow_reverse=*/true);

    pose_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("target_pose", 1);
    state_pub_ = pnh.advertise<std_msgs::String>("state", 1);
    image_transport::ImageTransport private_transport(pnh);
    debug_pub_ = private_transport.advertise("debug_image", 1);
    if (publish_tf_) tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
    camera_info_sub_ = nh.subscribe("camera_info", 1, &ParkerNodelet::onCameraInfo, this);
    image_transport::ImageTransport transport(nh);
    image_sub_ = transport.subscribe("image", 1, &ParkerNodelet::onImage, this);
    NODELET_INFO("parking in front of the %s at %.2f m", cfg.target.c_str(), cfg.standoff);
  }

  // Every callback runs guarded: an exception drops the message, never the node.
  void onCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    guardedCallback("camera_info", [&] { handleCameraInfo(info); });
  }

  void handleCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    std::lock_guard<std::mutex> lock(mutex_);
    bool changed = false;  // the intrinsics are copied on every message either way
    const std::string error = updateIntrinsics(*info, camera_, changed);
    if (!error.empty()) {
      NODELET_ERROR_THROTTLE(5.0, "ignoring camera_info: %s", error.c_str());
      return;
    }
    servo_->setIntrinsics(camera_);  // it keeps the marker inside this camera's view
    has_intrinsics_ = true;
  }

  void onImage(const sensor_msgs::ImageConstPtr& msg) {
    guardedCallback("image", [&] { handleImage(msg); });
  }

  void handleImage(const sensor_msgs::ImageConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::string error;
    const cv_bridge::CvImageConstPtr frame = bgrView(msg, error);
    if (!frame) {
      NODELET_ERROR_THROTTLE(1.0, "dropping frame: %s", error.c_str());
      output_->frameDropped(error);
      return;
    }
    output_->frameArrived();
    std::optional<MarkerObservation> marker;
    Twist2D desired;
    if (!has_intrinsics_) {
      // No pose without intrinsics; the robot holds still rather than search blind.
      NODELET_ERROR_THROTTLE(2.0, "no usable camera_info on %s yet: holding still",
                             camera_info_sub_.getTopic().c_str());
    } else {
      cv::Mat gray;
      cv::cvtColor(frame->image, gray, cv::COLOR_BGR2GRAY);
      marker = detector_->detect(gray, camera_);
      desired = servo_->update(marker, CommandOutput::frameTime(msg->header).toSec());
    }
    std_msgs::String state;
    state.data = has_intrinsics_ ? toString(servo_->state()) : "searching";
    // Idle once parked (the servo then commands zero): a push out of tolerance re-activates it.
    const bool parked = has_intrinsics_ && servo_->state() == ParkingState::kParked;
    output_->send(msg->header, desired, !parked, state.data);
    state_pub_.publish(state);
    if (marker) publishPose(msg->header, *marker);
    if (debug_pub_.getNumSubscribers() > 0) publishDebug(*frame, marker, state.data);
  }

  void publishPose(const std_msgs::Header& header, const MarkerObservation& marker) {
    geometry_msgs::PoseStamped pose;
    pose.header = header;
    pose.pose.position.x = marker.translation[0];
    pose.pose.position.y = marker.translation[1];
    pose.pose.position.z = marker.translation[2];
    const cv::Matx33d& r = marker.rotation;
    tf2::Quaternion q;
    tf2::Matrix3x3(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2))
        .getRotation(q);
    pose.pose.orientation.w = q.w();
    pose.pose.orientation.x = q.x();
    pose.pose.orientation.y = q.y();
    pose.pose.orientation.z = q.z();
    pose_pub_.publish(pose);
    if (tf_broadcaster_) {
      geometry_msgs::TransformStamped transform;
      transform.header = header;
      transform.child_frame_id = marker_frame_;
      transform.transform.translation.x = marker.translation[0];
      transform.transform.translation.y = marker.translation[1];
      transform.transform.translation.z = marker.translation[2];
      transform.transform.rotation = pose.pose.orientation;
      tf_broadcaster_->sendTransform(transform);
    }
  }

  void publishDebug(const cv_bridge::CvImage& frame, const std::optional<MarkerObservation>& marker,
                    const std::string& state) {
    cv_bridge::CvImage debug(frame.header, "bgr8", frame.image.clone());
    if (marker) {
      std::vector<cv::Point> outline;
      for (const cv::Point2d& corner : marker->corners) outline.emplace_back(corner);
      cv::polylines(debug.image, outline, true, cv::Scalar(0, 255, 255), 2);
      // Axes from the marker centre: x red, y green, z blue, each half the marker's width.
      const double half = cv::norm(marker->corners[1] - marker->corners[0]) > 0
                              ? 0.5 * cv::norm(marker->translation) *
                                    cv::norm(marker->corners[1] - marker->corners[0]) / camera_.fx
                              : 0.1;
      const std::vector<cv::Point3d> axes = {{0, 0, 0}, {half, 0, 0}, {0, half, 0}, {0, 0, half}};
      cv::Vec3d rvec;
      cv::Rodrigues(marker->rotation, rvec);
      const cv::Matx33d k(camera_.fx, 0, camera_.cx, 0, camera_.fy, camera_.cy, 0, 0, 1);
      std::vector<cv::Point2d> projected;
      cv::projectPoints(axes, rvec, marker->translation, k, cv::noArray(), projected);
      const cv::Scalar colours[] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}};
      for (int i = 0; i < 3; ++i) {
        cv::line(debug.image, projected[0], projected[i + 1], colours[i], 2);
      }
      cv::putText(debug.image, "id " + std::to_string(marker->id), outline[0] - cv::Point(0, 8),
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 255, 255), 2);
    }
    cv::putText(debug.image, state, cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.7,
                cv::Scalar(255, 255, 255), 2);
    debug_pub_.publish(debug.toImageMsg());
  }

  std::mutex mutex_;
  std::unique_ptr<MarkerDetector> detector_;
  std::unique_ptr<ParkingServo> servo_;
  CameraGeometry camera_;
  bool has_intrinsics_ = false;
  bool publish_tf_ = false;
  std::string marker_frame_;
  std::unique_ptr<CommandOutput> output_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::Publisher pose_pub_;
  ros::Publisher state_pub_;
  image_transport::Publisher debug_pub_;
  ros::Subscriber camera_info_sub_;
  image_transport::Subscriber image_sub_;
};

std::unique_ptr<nodelet::Nodelet> makeParkerNodelet() { return std::make_unique<ParkerNodelet>(); }

}  // namespace follow_bot

PLUGINLIB_EXPORT_CLASS(follow_bot::ParkerNodelet, nodelet::Nodelet)
