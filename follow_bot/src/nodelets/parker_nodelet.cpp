// Parker: find the parking marker (an AprilTag or a textured sign) and servo the robot to park
// square in front of it. One camera frame in, one status out; a Twist until it is parked.
//
// Thin wiring around a MarkerDetector (TagDetector or SignDetector, by ~target) and
// ParkingServo; BehaviourNodelet adds the camera topics, frame checks, limits (reversing
// allowed), the frame watchdog, the final stop and dynamic_reconfigure (cfg/Parker.cfg).
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <std_msgs/String.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>
#include <tf2_ros/transform_broadcaster.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "follow_bot/ParkerConfig.h"
#include "follow_bot/marker_target.h"
#include "follow_bot/parking_servo.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot/sign_detector.h"
#include "follow_bot/tag_detector.h"
#include "follow_bot_common/ros/behaviour_nodelet.h"

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

class ParkerNodelet : public BehaviourNodelet<ParkerConfig> {
 public:
  ParkerNodelet() : BehaviourNodelet({/*allow_reverse=*/true}) {}

 private:
  void setup(ros::NodeHandle&, ros::NodeHandle& pnh, const ParkerConfig& config) override {
    NODELET_INFO("parking in front of the %s at %.2f m", config.target.c_str(), config.standoff);
  }

  // A new configuration starts a fresh approach.
  void configure(const ParkerConfig& config) override {
    std::unique_ptr<MarkerDetector> detector = makeDetector(config);
    servo_ = std::make_unique<ParkingServo>(servoConfig(config, camera()));
    detector_ = std::move(detector);
    marker_frame_ = config.marker_frame;
    if (!config.publish_tf) {
      tf_broadcaster_.reset();
    } else if (!tf_broadcaster_) {
      tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
    }
  }

  void advertise(ros::NodeHandle&, ros::NodeHandle& pnh) override {
    pose_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("target_pose", 1);
    state_pub_ = pnh.advertise<std_msgs::String>("state", 1);
  }

  // The servo keeps the marker inside this camera's view; its approach goes on.
  void intrinsicsArrived(bool) override { servo_->setIntrinsics(camera()); }

  Decision step(const Frame& frame) override {
    marker_.reset();
    Twist2D desired;
    if (!hasIntrinsics()) {
      // No pose without intrinsics; the robot holds still rather than search blind.
      NODELET_ERROR_THROTTLE(2.0, "no usable camera_info on %s yet: holding still",
                             cameraInfoTopic().c_str());
    } else {
      cv::Mat gray;
      cv::cvtColor(frame.image, gray, cv::COLOR_BGR2GRAY);
      marker_ = detector_->detect(gray, camera());
      desired = servo_->update(marker_, frame.time);
    }
    state_ = hasIntrinsics() ? toString(servo_->state()) : "searching";
    // Idle once parked (the servo then commands zero): a push out of tolerance re-activates it.
    const bool parked = hasIntrinsics() && servo_->state() == ParkingState::kParked;
    return {desired, !parked, state_};
  }

  void report(const Frame& frame, const Twist2D&) override {
    std_msgs::String state;
    state.data = state_;
    state_pub_.publish(state);
    if (marker_) publishPose(frame.header, *marker_);
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

  void drawDebug(cv::Mat& canvas) override {
    const std::optional<MarkerObservation>& marker = marker_;
    if (marker) {
      std::vector<cv::Point> outline;
      for (const cv::Point2d& corner : marker->corners) outline.emplace_back(corner);
      cv::polylines(canvas, outline, true, cv::Scalar(0, 255, 255), 2);
      // Axes from the marker centre: x red, y green, z blue, each half the marker's width.
      const double half = cv::norm(marker->corners[1] - marker->corners[0]) > 0
                              ? 0.5 * cv::norm(marker->translation) *
                                    cv::norm(marker->corners[1] - marker->corners[0]) / camera().fx
                              : 0.1;
      const std::vector<cv::Point3d> axes = {{0, 0, 0}, {half, 0, 0}, {0, half, 0}, {0, 0, half}};
      cv::Vec3d rvec;
      cv::Rodrigues(marker->rotation, rvec);
      const cv::Matx33d k(camera().fx, 0, camera().cx, 0, camera().fy, camera().cy, 0, 0, 1);
      std::vector<cv::Point2d> projected;
      cv::projectPoints(axes, rvec, marker->translation, k, cv::noArray(), projected);
      const cv::Scalar colours[] = {{0, 0, 255}, {0, 255, 0}, {255, 0, 0}};
      for (int i = 0; i < 3; ++i) {
        cv::line(canvas, projected[0], projected[i + 1], colours[i], 2);
      }
      cv::putText(canvas, "id " + std::to_string(marker->id), outline[0] - cv::Point(0, 8),
                  cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 255, 255), 2);
    }
    cv::putText(canvas, state_, cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.7,
                cv::Scalar(255, 255, 255), 2);
  }

  std::unique_ptr<MarkerDetector> detector_;
  std::unique_ptr<ParkingServo> servo_;
  std::string marker_frame_;
  std::optional<MarkerObservation> marker_;  // the last frame's
  std::string state_;                        // the last frame's
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::Publisher pose_pub_;
  ros::Publisher state_pub_;
};

}  // namespace follow_bot

FOLLOW_BOT_EXPORT_NODELET(ParkerNodelet)
