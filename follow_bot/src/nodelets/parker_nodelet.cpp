// Parker: find the parking marker (an AprilTag or a textured sign) and servo the robot to park
// square in front of it. One camera frame in, one status out; a Twist until it is parked.
//
// Thin wiring around a MarkerDetector (TagDetector or SignDetector, by ~target) and
// ParkingServo; BehaviourNodelet adds the camera topics, frame checks, limits (reversing
// allowed), the frame watchdog, the final stop and dynamic_reconfigure (cfg/Parker.cfg).
#include <memory>
#include <optional>
#include <string>

#include <geometry_msgs/PoseStamped.h>
#include <std_msgs/String.h>
#include <tf2_ros/transform_broadcaster.h>
#include <opencv2/imgproc.hpp>

#include "follow_bot/ParkerConfig.h"
#include "follow_bot/common.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot_common/ros/behaviour_nodelet.h"
#include "messages.h"
#include "settings.h"

namespace follow_bot {

class ParkerNodelet : public BehaviourNodelet<ParkerConfig> {
 public:
  ParkerNodelet() : BehaviourNodelet({/*allow_reverse=*/true}) {}

 private:
  void setup(ros::NodeHandle& /*nh*/, ros::NodeHandle& /*pnh*/,
             const ParkerConfig& config) override {
    NODELET_INFO("parking in front of the %s at %.2f m", config.target.c_str(), config.standoff);
  }

  // A new configuration starts a fresh approach.
  void configure(const ParkerConfig& config) override {
    std::unique_ptr<MarkerDetector> detector = makeMarkerDetector(config);
    servo_ = std::make_unique<ParkingServo>(parkingServoConfig(config, camera()));
    detector_ = std::move(detector);
    marker_frame_ = config.marker_frame;
    standoff_ = config.standoff;
    if (!config.publish_tf) {
      tf_broadcaster_.reset();
    } else if (!tf_broadcaster_) {
      tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
    }
  }

  void advertise(ros::NodeHandle& /*nh*/, ros::NodeHandle& pnh) override {
    pose_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("target_pose", 1);
    state_pub_ = pnh.advertise<std_msgs::String>("state", 1);
  }

  // The servo keeps the marker inside this camera's view; its approach goes on.
  void intrinsicsArrived(bool /*changed*/) override { servo_->setIntrinsics(camera()); }

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

  void report(const Frame& frame, const Twist2D& /*sent*/) override {
    std_msgs::String state;
    state.data = state_;
    state_pub_.publish(state);
    if (!marker_) return;
    const geometry_msgs::PoseStamped pose = markerPose(frame.header, *marker_);
    pose_pub_.publish(pose);
    if (tf_broadcaster_) tf_broadcaster_->sendTransform(markerTransform(pose, marker_frame_));
  }

  void drawDebug(cv::Mat& canvas) override {
    if (marker_) drawMarker(canvas, *marker_, camera());
    cv::putText(canvas, state_, cv::Point(10, 25), cv::FONT_HERSHEY_SIMPLEX, 0.7,
                cv::Scalar(255, 255, 255), 2);
  }

  // The marker (its outward normal from its centre) and the pose the robot parks at: standoff
  // in front of it, facing it.
  void addMarkers(RvizMarkers& markers) override {
    if (!marker_) return;
    const MarkerInBase placed = markerInBase(*marker_, camera());
    const cv::Point3d centre(placed.centre);
    markers.sphere("marker", 0, centre, 0.08, rgba(1.0, 1.0, 0.0));
    markers.arrow("marker", 1, centre, placed.outward_normal, 0.3, rgba(1.0, 1.0, 0.0));
    const cv::Vec2d out =
        cv::normalize(cv::Vec2d(placed.outward_normal[0], placed.outward_normal[1]));
    const cv::Point3d goal(centre.x + standoff_ * out[0], centre.y + standoff_ * out[1], 0.0);
    markers.arrow("goal", 0, goal, cv::Vec3d(-out[0], -out[1], 0.0), 0.3, rgba(0.0, 1.0, 0.0));
  }

  std::unique_ptr<MarkerDetector> detector_;
  std::unique_ptr<ParkingServo> servo_;
  std::string marker_frame_;
  double standoff_ = 0.0;  // m, base origin to the marker's centre along its normal when parked
  std::optional<MarkerObservation> marker_;  // the last frame's
  std::string state_;                        // the last frame's
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  ros::Publisher pose_pub_;
  ros::Publisher state_pub_;
};

}  // namespace follow_bot

FOLLOW_BOT_EXPORT_NODELET(ParkerNodelet)

follow_bot_common::NodeHelp follow_bot::parkerHelp() {
  return behaviourHelp(
      "Parks the robot square in front of an AprilTag or a textured sign (~target).",
      {{"out", "~target_pose", "geometry_msgs/PoseStamped", "the marker in the camera frame"},
       {"out", "~state", "std_msgs/String", "searching, approaching, aligning, parked or lost"},
       {"out", "~debug_image", "sensor_msgs/Image", "lazy: outline, id, axes"},
       {"out", "~markers", "visualization_msgs/MarkerArray",
        "lazy, in ~base_frame: the marker's centre and normal, the parking goal"}});
}
