// Panorama: on a ~capture call the robot turns in place through a set of headings, grabs a
// frame at each, stitches them and publishes the panorama (latched) on ~panorama.
//
// Thin wiring around PanoramaSession (the request, the turn, the stitch, when to give up);
// BehaviourNodelet adds the camera topics, frame checks, limits, the frame watchdog, ~enable,
// ~status, diagnostics and the final stop. One camera frame in, one status out; a Twist only
// during a capture (idle otherwise: no cmd_vel at all). The ~capture call waits on a thread of
// its own (BlockingService) while the frames drive the capture.
#include <memory>
#include <string>

#include <nav_msgs/Odometry.h>
#include <std_srvs/Trigger.h>

#include "follow_bot/PanoramaConfig.h"
#include "follow_bot/common.h"
#include "follow_bot/panorama_session.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot_common/ros/behaviour_nodelet.h"
#include "follow_bot_common/ros/blocking_service.h"
#include "settings.h"

namespace follow_bot {

class PanoramaNodelet : public BehaviourNodelet<PanoramaConfig> {
 public:
  // The ~params are read once: a capture must keep the schedule it started with.
  PanoramaNodelet()
      : BehaviourNodelet({/*allow_reverse=*/false, /*live_reconfigure=*/false,
                          /*debug_image=*/false, /*markers=*/false}) {}

 private:
  void setup(ros::NodeHandle& /*nh*/, ros::NodeHandle& pnh,
             const PanoramaConfig& /*config*/) override {
    matching_ = readConfig<image_converter::MatchingConfig>(pnh);  // image_converter's ~params
  }

  void configure(const PanoramaConfig& config) override {
    session_ = std::make_unique<PanoramaSession>(panoramaSettings(config, matching_));
  }

  void advertise(ros::NodeHandle& nh, ros::NodeHandle& pnh) override {
    panorama_pub_ = pnh.advertise<sensor_msgs::Image>("panorama", 1, /*latch=*/true);
    odom_sub_ = subscribe<nav_msgs::Odometry>(nh, "odom", [this](const nav_msgs::Odometry& odom) {
      const geometry_msgs::Quaternion& q = odom.pose.pose.orientation;
      if (!session_->orientation(q.x, q.y, q.z, q.w)) {
        NODELET_ERROR_THROTTLE(5.0, "ignoring odometry: its orientation is not a unit quaternion");
      }
    });
    addDiagnostics("panorama", [this] { return session_->report(); });
    capture_srv_ =
        std::make_unique<BlockingService>(pnh, "capture", &PanoramaNodelet::onCapture, this);
  }

  // The intrinsics and the mounting are read from camera() when stitching: a capture keeps its
  // schedule.
  void intrinsicsArrived(bool /*changed*/) override {}
  void mountingChanged() override {}

  bool onCapture(std_srvs::Trigger::Request& /*request*/, std_srvs::Trigger::Response& response) {
    std::unique_lock<boost::recursive_mutex> lock(mutex());
    const std::string missing = !session_->hasPose() ? "no pose yet on " + odom_sub_.getTopic()
                                : !hasIntrinsics()   ? "no camera_info yet on " + cameraInfoTopic()
                                : !session_->framesArriving(ros::WallTime::now().toSec())
                                    ? "no camera frames on " + imageTopic()
                                    : "";
    if (session_->busy() || !missing.empty()) {
      response.message =
          session_->busy() ? "a capture is already running" : "cannot capture: " + missing;
      return true;
    }
    session_->request(ros::Time::now().toSec());
    capture_srv_->waitUntil(lock, [this] {  // frames drive the capture; this watches its end
      if (session_->abortIfStalled(ros::WallTime::now().toSec(), ros::Time::now().toSec(),
                                   !ros::ok())) {
        output().stop();  // the watchdog has mostly done so already
      }
      updateDiagnostics();
      return !session_->busy();
    });
    updateDiagnostics(/*force=*/true);
    response.success = session_->last()->success;
    response.message = session_->last()->message;
    return true;
  }

  Decision step(const Frame& frame) override {
    Twist2D desired;
    desired.angular = session_->update(frame.image, ros::WallTime::now().toSec());
    return {desired, session_->turning(), session_->turning() ? "capturing" : "idle"};
  }

  // The frame is answered first: stitching takes a while and the base should not wait for it.
  void report(const Frame& frame, const Twist2D& /*sent*/) override {
    if (!session_->stitchDue()) return;
    const CaptureStitch stitched = session_->stitch(camera());
    capture_srv_->notify();
    if (!stitched.ok()) {
      NODELET_ERROR("panorama: %s", stitched.message.c_str());
      return;
    }
    NODELET_INFO("panorama: %s", stitched.message.c_str());
    panorama_pub_.publish(cv_bridge::CvImage(frame.header, "bgr8", stitched.panorama).toImageMsg());
  }

  image_converter::MatchingConfig matching_;
  std::unique_ptr<PanoramaSession> session_;
  ros::Publisher panorama_pub_;
  ros::Subscriber odom_sub_;
  std::unique_ptr<BlockingService> capture_srv_;  // last: its thread ends before the rest goes
};

}  // namespace follow_bot

FOLLOW_BOT_EXPORT_NODELET(PanoramaNodelet)

follow_bot_common::NodeHelp follow_bot::panoramaHelp() {
  return behaviourHelp(
      "Turns on the spot on request, photographing, and stitches the photographs into a "
      "panorama.",
      {{"in", "odom", "nav_msgs/Odometry", "the yaw the turn is measured by"},
       {"service", "~capture", "std_srvs/Trigger", "one capture; replies when it is over"},
       {"out", "~panorama", "sensor_msgs/Image", "latched, bgr8"}});
}
