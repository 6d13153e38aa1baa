// Panorama: on a ~capture call the robot turns in place through a set of headings, grabs a
// frame at each, stitches them and publishes the panorama (latched) on ~panorama.
//
// Thin wiring around image_converter's PanoramaCapture (the turn schedule) and stitching core;
// CommandOutput adds limits, the frame watchdog, ~enable, ~status and the final stop. One camera
// frame in, one status out; a Twist only during a capture (idle otherwise: no cmd_vel at all).
// The service waits on its own callback queue while the frames drive the capture on the
// nodelet's queue.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <cv_bridge/cv_bridge.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <image_transport/image_transport.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <sensor_msgs/CameraInfo.h>
#include <std_srvs/Trigger.h>
#include <pluginlib/class_list_macros.hpp>

#include "follow_bot/PanoramaConfig.h"
#include "follow_bot/ros/command_output.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot/ros/params.h"
#include "image_converter/panorama_capture.h"
#include "image_converter/ros/checked_nodelet.h"
#include "image_converter/ros/frame_msg.h"
#include "image_converter/stitching.h"

namespace follow_bot {

using image_converter::bgrView;
using image_converter::guardedCallback;
using image_converter::MatchOptions;
using image_converter::PanoramaCapture;
using image_converter::PanoramaCaptureConfig;
using image_converter::StitchResult;
using image_converter::TurningCamera;
using image_converter::wrapAngle;

namespace {

constexpr double kPi = 3.141592653589793;

enum class StitchMethod { kAuto, kFeatures, kRotation };

// "<rule>, got <a> and <b>" unless `ok`: a rule linking two ~params, for a start-up error.
void requireLinked(bool ok, const std::string& rule, double a, double b) {
  if (ok) return;
  std::ostringstream error;
  error << rule << ", got " << a << " and " << b;
  throw std::invalid_argument(error.str());
}

double yawOf(const nav_msgs::Odometry& odom) {
  const geometry_msgs::Quaternion& q = odom.pose.pose.orientation;
  return image_converter::yawOfQuaternion(q.x, q.y, q.z, q.w);
}

}  // namespace

class PanoramaNodelet : public image_converter::CheckedNodelet {
 public:
  ~PanoramaNodelet() override {
    if (spinner_) spinner_->stop();  // output_ then sends the final zero
  }

 private:
  void init() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    readParams(pnh);  // throws on bad ~params
    output_ = std::make_unique<CommandOutput>(nh, pnh);

    panorama_pub_ = pnh.advertise<sensor_msgs::Image>("panorama", 1, /*latch=*/true);
    camera_info_sub_ = nh.subscribe("camera_info", 1, &PanoramaNodelet::onCameraInfo, this);
    odom_sub_ = nh.subscribe("odom", 1, &PanoramaNodelet::onOdom, this);
    image_transport::ImageTransport transport(nh);
    image_sub_ = transport.subscribe("image", 1, &PanoramaNodelet::onImage, this);

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

  // Ranges are the .cfg's (readConfig checks them); the rules linking two ~params are here.
  void readParams(const ros::NodeHandle& pnh) {
    const PanoramaConfig cfg = readConfig<PanoramaConfig>(pnh);
    requireLinked(cfg.step_angle_deg <= cfg.total_angle_deg,
                  "~step_angle_deg must be at most ~total_angle_deg", cfg.step_angle_deg,
                  cfg.total_angle_deg);
    requireLinked(cfg.min_angular <= cfg.max_angular, "~min_angular must be at most ~max_angular",
                  cfg.min_angular, cfg.max_angular);
    requireLinked(cfg.yaw_tolerance_deg < cfg.step_angle_deg / 2.0,
                  "~yaw_tolerance_deg must be below ~step_angle_deg / 2", cfg.yaw_tolerance_deg,
                  cfg.step_angle_deg);
    PanoramaCaptureConfig capture;
    capture.total_angle = cfg.total_angle_deg * kPi / 180.0;
    capture.step_angle = cfg.step_angle_deg * kPi / 180.0;
    capture.max_turn_rate = cfg.max_angular;
    capture.min_turn_rate = cfg.min_angular;
    capture.yaw_gain = cfg.yaw_gain;
    capture.yaw_tolerance = cfg.yaw_tolerance_deg * kPi / 180.0;
    capture.settle_frames = cfg.settle_frames;
    capture.return_to_start = cfg.return_to_start;
    capture_ = std::make_unique<PanoramaCapture>(capture);  // validated above and by the ranges

    if (!parseDetector(cfg.detector, match_options_.detector)) {
      throw std::invalid_argument("~detector must be orb or sift, got '" + cfg.detector + "'");
    }
    match_options_.min_inliers = cfg.min_inliers;

    if (cfg.stitch_method == "auto") {
      method_ = StitchMethod::kAuto;
    } else if (cfg.stitch_method == "features") {
      method_ = StitchMethod::kFeatures;
    } else if (cfg.stitch_method == "rotation") {
      method_ = StitchMethod::kRotation;
    } else {
      throw std::invalid_argument("~stitch_method must be auto, features or rotation, got '" +
                                  cfg.stitch_method + "'");
    }
    frame_timeout_ = cfg.frame_timeout;
    capture_timeout_ = cfg.capture_timeout;

    camera_.pitch = param(pnh, "camera_pitch_deg", 0.0) * kPi / 180.0;
    if (!(std::abs(camera_.pitch) < 1.5)) {
      throw std::invalid_argument("~camera_pitch_deg must be within +-85 deg");
    }
  }

  // Every callback runs guarded: an exception drops the message, never the node.
  void onCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    guardedCallback("camera_info", [&] { handleCameraInfo(info); });
  }

  void handleCameraInfo(const sensor_msgs::CameraInfoConstPtr& info) {
    std::lock_guard<std::mutex> lock(mutex_);
    TurningCamera updated = camera_;
    updated.fx = info->K[0];
    updated.fy = info->K[4];
    updated.cx = info->K[2];
    updated.cy = info->K[5];
    const std::string error = validate(updated);
    if (!error.empty()) {
      NODELET_ERROR_THROTTLE(5.0, "ignoring camera_info: %s", error.c_str());
      return;
    }
    camera_ = updated;
    has_intrinsics_ = true;
  }

  void onOdom(const nav_msgs::OdometryConstPtr& odom) {
    guardedCallback("odom", [&] { handleOdom(odom); });
  }

  void handleOdom(const nav_msgs::OdometryConstPtr& odom) {
    const double yaw = yawOf(*odom);
    if (!std::isfinite(yaw)) {
      NODELET_ERROR_THROTTLE(5.0, "ignoring odometry: its orientation is not a unit quaternion");
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    yaw_ = yaw;
  }

  bool onCapture(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& response) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (start_requested_ || capture_->active()) {
      response.message = "a capture is already running";
      return true;
    }
    const double since_frame = ros::WallTime::now().toSec() - last_frame_wall_;
    if (!yaw_ || !has_intrinsics_ || since_frame > frame_timeout_) {
      response.message =
          std::string("cannot capture: ") +
          (!yaw_              ? "no pose yet on " + odom_sub_.getTopic()
           : !has_intrinsics_ ? "no camera_info yet on " + camera_info_sub_.getTopic()
                              : "no camera frames on " + image_sub_.getTopic());
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
      const bool timed_out = ros::Time::now().toSec() - started.toSec() > capture_timeout_;
      if (silent > frame_timeout_ || timed_out || !ros::ok()) {
        capture_->abort();
        start_requested_ = false;
        output_->stop();  // the watchdog has mostly done so already
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

  void onImage(const sensor_msgs::ImageConstPtr& msg) {
    guardedCallback("image", [&] { handleImage(msg); });
  }

  void handleImage(const sensor_msgs::ImageConstPtr& msg) {
    std::unique_lock<std::mutex> lock(mutex_);
    std::string error;
    const cv_bridge::CvImageConstPtr frame = bgrView(msg, error);
    updater_->update();
    if (!frame) {
      NODELET_ERROR_THROTTLE(1.0, "dropping frame: %s", error.c_str());
      output_->frameDropped(error);
      return;
    }
    output_->frameArrived();
    last_frame_wall_ = ros::WallTime::now().toSec();

    if (start_requested_ && yaw_) {
      start_requested_ = false;
      capture_->start(*yaw_);
      frames_.clear();
      yaws_.clear();
    }
    PanoramaCapture::Step step;
    if (capture_->active() && yaw_) step = capture_->update(*yaw_);
    if (step.grab) {
      frames_.push_back(frame->image.clone());
      yaws_.push_back(*yaw_);
    }
    Twist2D desired;
    desired.angular = step.angular;
    const bool capturing = capture_->active();
    output_->send(msg->header, desired, capturing, capturing ? "capturing" : "idle");
    if (!step.finished) return;

    // Answer this frame first: stitching takes a while and the base should not wait for it.
    Outcome outcome;
    try {  // the caller must get a reply whatever the stitcher does
      outcome = stitchAndPublish(msg->header);
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

  // The "<node>: panorama" status on /diagnostics. Called by updater_ with mutex_ held.
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
    const double span_deg = std::abs(wrapAngle(yaws_.front() - yaws_.back())) * 180.0 / kPi;
    std::string notes;
    StitchResult result;
    std::string used;
    if (method_ != StitchMethod::kRotation) {
      result = stitchMany(frames_, match_options_);
      used = "features (cv::Stitcher, " + detectorName(match_options_.detector) + ")";
      if (result.ok()) result.error = checkWidth(result.panorama.cols);
      if (!result.ok() && method_ == StitchMethod::kAuto) {
        notes = "; feature stitching failed (" + result.error + "), used the odometry yaws";
      }
    }
    if (method_ == StitchMethod::kRotation || (method_ == StitchMethod::kAuto && !result.ok())) {
      result = stitchByRotation(frames_, yaws_, camera_);
      used = "rotation (odometry yaws)";
    }
    if (!result.ok()) return {false, "stitching failed: " + result.error};
    cv_bridge::CvImage image(header, "bgr8", result.panorama);
    panorama_pub_.publish(image.toImageMsg());
    char summary[160];
    std::snprintf(summary, sizeof summary, "%d x %d px from %zu frames over %.0f deg by ",
                  result.panorama.cols, result.panorama.rows, frames_.size(), span_deg);
    return {true, summary + used + notes};
  }

  // A feature panorama must be about as wide as the turn says: fx * (span + field of view).
  // Wrong links between look-alike views give panoramas of the wrong width.
  std::string checkWidth(int width) const {
    const double span = std::abs(wrapAngle(yaws_.front() - yaws_.back()));
    const double fov = 2.0 * std::atan(frames_.front().cols / (2.0 * camera_.fx));
    const double expected = camera_.fx * (span + fov);
    if (std::abs(width - expected) <= 0.15 * expected) return "";
    return "panorama " + std::to_string(width) + " px wide where the turn predicts " +
           std::to_string(static_cast<int>(expected)) + " px";
  }

  std::mutex mutex_;
  std::condition_variable changed_;
  std::unique_ptr<PanoramaCapture> capture_;
  std::unique_ptr<CommandOutput> output_;
  MatchOptions match_options_;
  StitchMethod method_ = StitchMethod::kAuto;
  TurningCamera camera_;
  bool has_intrinsics_ = false;
  std::optional<double> yaw_;
  double frame_timeout_ = 1.0;
  double capture_timeout_ = 120.0;
  double last_frame_wall_ = -1e9;
  bool start_requested_ = false;
  std::optional<Outcome> outcome_;
  std::vector<cv::Mat> frames_;
  std::vector<double> yaws_;
  std::optional<Outcome> last_outcome_;
  long aborts_ = 0;
  std::unique_ptr<diagnostic_updater::Updater> updater_;

  ros::Publisher panorama_pub_;
  ros::Subscriber camera_info_sub_, odom_sub_;
  image_transport::Subscriber image_sub_;
  ros::CallbackQueue service_queue_;
  ros::ServiceServer capture_srv_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
};

std::unique_ptr<nodelet::Nodelet> makePanoramaNodelet() {
  return std::make_unique<PanoramaNodelet>();
}

}  // namespace follow_bot

PLUGINLIB_EXPORT_CLASS(follow_bot::PanoramaNodelet, nodelet::Nodelet)
