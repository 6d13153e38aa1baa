// Panorama: on a ~capture call the robot turns in place through a set of headings, grabs a
// frame at each, stitches them and publishes the panorama (latched) on ~panorama.
//
// Thin wiring around PanoramaCapture (the turn schedule) and stitchCapture (the stitch);
// BehaviourNodelet adds the camera topics, frame checks, limits, the frame watchdog, ~enable,
// ~status and the final stop. One camera frame in, one status out; a Twist only during a
// capture (idle otherwise: no cmd_vel at all).
// The service waits on its own callback queue while the frames drive the capture on the
// nodelet's queue.
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <nav_msgs/Odometry.h>
#include <ros/callback_queue.h>
#include <std_srvs/Trigger.h>

#include "follow_bot/PanoramaConfig.h"
#include "follow_bot/panorama_capture.h"
#include "follow_bot/panorama_stitch.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot_common/ros/behaviour_nodelet.h"
#include "settings.h"

namespace follow_bot {

namespace {

double yawOf(const nav_msgs::Odometry& odom) {
  const geometry_msgs::Quaternion& q = odom.pose.pose.orientation;
  return yawOfQuaternion(q.x, q.y, q.z, q.w);
}

}  // namespace

class PanoramaNodelet : public BehaviourNodelet<PanoramaConfig> {
 public:
  // The ~params are read once: a capture must keep the schedule it started with.
  PanoramaNodelet()
      : BehaviourNodelet({/*allow_reverse=*/false, /*live_reconfigure=*/false,
                          /*debug_image=*/false}) {}
  ~PanoramaNodelet() override {
    if (spinner_) spinner_->stop();  // output() then sends the final zero
  }

 private:
  void configure(const PanoramaConfig& config) override {
    settings_ = panoramaSettings(config);
    capture_ = std::make_unique<PanoramaCapture>(settings_.capture);
  }

  void advertise(ros::NodeHandle& nh, ros::NodeHandle& pnh) override {
    panorama_pub_ = pnh.advertise<sensor_msgs::Image>("panorama", 1, /*latch=*/true);
    odom_sub_ = subscribe<nav_msgs::Odometry>(nh, "odom", [this](const nav_msgs::Odometry& odom) {
      const double yaw = yawOf(odom);
      if (!std::isfinite(yaw)) {
        NODELET_ERROR_THROTTLE(5.0, "ignoring odometry: its orientation is not a unit quaternion");
        return;
      }
      yaw_ = yaw;
    });

    updater_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, pnh.getNamespace());
    updater_->setHardwareID("none");
    updater_->add("panorama", this, &PanoramaNodelet::reportStatus);

    // The service blocks until the capture ends, so it gets a queue and thread of its own.
    ros::NodeHandle service_nh(pnh);
    service_nh.setCallbackQueue(&service_queue_);
    capture_srv_ = service_nh.advertiseService("capture", &PanoramaNodelet::onCapture, this);
    spinner_ = std::make_unique<ros::AsyncSpinner>(1, &service_queue_);
    spinner_->start();
  }

  // The intrinsics and the mounting are read from camera() when stitching: a capture keeps its
  // schedule.
  void intrinsicsArrived(bool) override {}
  void mountingChanged() override {}

  bool onCapture(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    std::unique_lock<boost::recursive_mutex> lock(mutex());
    if (start_requested_ || capture_->active()) {
      response.message = "a capture is already running";
      return true;
    }
    const double since_frame = ros::WallTime::now().toSec() - last_frame_wall_;
    if (!yaw_ || !hasIntrinsics() || since_frame > settings_.frame_timeout) {
      response.message = std::string("cannot capture: ") +
                         (!yaw_              ? "no pose yet on " + odom_sub_.getTopic()
                          : !hasIntrinsics() ? "no camera_info yet on " + cameraInfoTopic()
                                             : "no camera frames on " + imageTopic());
      return true;
    }
    start_requested_ = true;
    outcome_.reset();
    const ros::Time started = ros::Time::now();
    // Frames drive the capture; this thread only watches for its end or for lost frames.
    while (!outcome_) {
      changed_.wait_for(lock, std::chrono::milliseconds(100));
      if (outcome_) break;
      const double silent = ros::WallTime::now().toSec() - last_frame_wall_;
      const bool timed_out = ros::Time::now().toSec() - started.toSec() > settings_.capture_timeout;
      if (silent > settings_.frame_timeout || timed_out || !ros::ok()) {
        capture_->abort();
        start_requested_ = false;
        output().stop();  // the watchdog has mostly done so already
        outcome_ = Outcome{false, timed_out ? "capture took longer than ~capture_timeout"
                                            : "camera frames stopped during the capture"};
        ++aborts_;
      }
      updater_->update();
    }
    last_outcome_ = *outcome_;
    updater_->force_update();
    response.success = outcome_->success;
    response.message = outcome_->message;
    return true;
  }

  Decision step(const Frame& frame) override {
    updater_->update();
    last_frame_wall_ = ros::WallTime::now().toSec();
    if (start_requested_ && yaw_) {
      start_requested_ = false;
      capture_->start(*yaw_);
      frames_.clear();
      yaws_.clear();
    }
    step_ = {};
    if (capture_->active() && yaw_) step_ = capture_->update(*yaw_);
    if (step_.grab) {
      frames_.push_back(frame.image.clone());
      yaws_.push_back(*yaw_);
    }
    Twist2D desired;
    desired.angular = step_.angular;
    const bool capturing = capture_->active();
    return {desired, capturing, capturing ? "capturing" : "idle"};
  }

  // The frame is answered first: stitching takes a while and the base should not wait for it.
  void report(const Frame& frame, const Twist2D&) override {
    if (!step_.finished) return;
    Outcome outcome;
    try {  // the caller must get a reply whatever the stitcher does
      outcome = stitchAndPublish(frame.header);
    } catch (const std::exception& error) {
      outcome = {false, std::string("stitching failed: ") + error.what()};
    }
    outcome_ = outcome;
    changed_.notify_all();
    if (outcome.success) {
      NODELET_INFO("panorama: %s", outcome.message.c_str());
    } else {
      NODELET_ERROR("panorama: %s", outcome.message.c_str());
    }
  }

  struct Outcome {
    bool success = false;
    std::string message;
  };

  // The "<node>: panorama" status on /diagnostics. Called by updater_ with mutex() held.
  void reportStatus(diagnostic_updater::DiagnosticStatusWrapper& status) {
    if (last_outcome_ && !last_outcome_->success) {
      status.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR, "last capture failed: %s",
                      last_outcome_->message.c_str());
    } else {
      status.summary(diagnostic_msgs::DiagnosticStatus::OK, "running");
    }
    status.add("state", start_requested_ || capture_->active() ? "capturing" : "idle");
    status.add("captures stopped for lost frames or time", aborts_);
    status.add("last capture", last_outcome_ ? last_outcome_->message : "none");
  }

  Outcome stitchAndPublish(const std_msgs::Header& header) {
    const CaptureStitch stitched =
        stitchCapture(frames_, yaws_, camera(), settings_.match, settings_.method);
    if (stitched.ok())
      panorama_pub_.publish(cv_bridge::CvImage(header, "bgr8", stitched.panorama).toImageMsg());
    return {stitched.ok(), stitched.message};
  }

  std::condition_variable_any changed_;  // with mutex(): a capture's outcome
  std::unique_ptr<PanoramaCapture> capture_;
  PanoramaSettings settings_;
  std::optional<double> yaw_;
  double last_frame_wall_ = -1e9;
  bool start_requested_ = false;
  PanoramaCapture::Step step_;  // the last frame's
  std::optional<Outcome> outcome_;
  std::vector<cv::Mat> frames_;
  std::vector<double> yaws_;
  std::optional<Outcome> last_outcome_;
  long aborts_ = 0;
  std::unique_ptr<diagnostic_updater::Updater> updater_;

  ros::Publisher panorama_pub_;
  ros::Subscriber odom_sub_;
  ros::CallbackQueue service_queue_;
  ros::ServiceServer capture_srv_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
};

}  // namespace follow_bot

FOLLOW_BOT_EXPORT_NODELET(PanoramaNodelet)
