// Follower: the lecture's Follow-Bot as a nodelet. One camera frame in, one status out; a Twist
// while it follows or searches, silence once it has given up.
//
// Thin wiring around LineDetector (band-only HSV threshold + moments) and a SteeringLaw (the
// lecture's, pd or path; makeSteeringLaw); BehaviourNodelet adds the camera topics, frame checks,
// limits, the frame watchdog and the final stop. Thresholds and gains are ~params, also live
// through dynamic_reconfigure.
#include <cmath>
#include <memory>
#include <optional>
#include <vector>

#include <nav_msgs/Odometry.h>

#include "follow_bot/FollowerConfig.h"
#include "follow_bot/FollowerStartupDefaults.h"
#include "follow_bot/common.h"
#include "follow_bot/latency_estimator.h"
#include "follow_bot/line_path.h"
#include "follow_bot/ros/nodelets.h"
#include "follow_bot_common/ros/behaviour_nodelet.h"
#include "messages.h"
#include "settings.h"

namespace follow_bot {

namespace {

// The floor arc the robot drives in `horizon_s` under `command` (from base_link's origin), in
// steps of `step_s`.
std::vector<cv::Point2d> predictedArc(const Twist2D& command, double horizon_s, double step_s) {
  std::vector<cv::Point2d> arc;
  for (double t = 0.0; t <= horizon_s + 1e-9; t += step_s) {
    arc.push_back(arcDisplacement(command.linear * t, command.angular * t));
  }
  return arc;
}

}  // namespace

class FollowerNodelet : public BehaviourNodelet<FollowerConfig> {
 private:
  void setup(ros::NodeHandle& nh, ros::NodeHandle& pnh, const FollowerConfig& /*config*/) override {
    // On by default: every real base publishes odom and lags its commands by 50-150 ms, which
    // the commands alone cannot tell path mode's memory.
    use_odom_ = param(pnh, "use_odom", FollowerStartupDefaults::use_odom);
    if (use_odom_) {
      odom_sub_ = subscribe<nav_msgs::Odometry>(nh, "odom", [this](const nav_msgs::Odometry& odom) {
        odom_twist_ = Twist2D{odom.twist.twist.linear.x, odom.twist.twist.angular.z};
        has_odom_ = true;
        latency_.measured(CommandOutput::frameTime(odom.header).toSec(), odom_twist_);
      });
    }
  }

  void advertise(ros::NodeHandle& /*nh*/, ros::NodeHandle& pnh) override {
    status_pub_ = pnh.advertise<LineStatus>("line", 1);
  }

  // New settings, or new intrinsics (path mode's ground geometry and where the bands land), start
  // with fresh controller state (a new law must not inherit the old one's).
  void configure(const FollowerConfig& config) override {
    settings_ = followerSettings(config);
    detector_ = std::make_unique<LineDetector>(settings_.detector, camera());
    placement_reported_ = false;
    // Until camera_info arrives path mode steers with pd.
    law_ = makeSteeringLaw(settings_.steering,
                           hasIntrinsics() ? std::optional(camera()) : std::nullopt);
  }

  // The base's measured motion (~use_odom) beats the commands for path mode's memory whenever
  // the base lags or slips.
  Twist2D steer(const LineMeasurement& seen, double stamp) {
    if (law_->mode() == SteeringMode::kPath && use_odom_ && !has_odom_) {
      // Said once, after a second of frames: odometry may well start after the camera.
      if (!first_path_stamp_) first_path_stamp_ = stamp;
      if (!odom_absence_said_ && stamp - *first_path_stamp_ >= 1.0) {
        odom_absence_said_ = true;
        NODELET_WARN(
            "~use_odom: no odometry on %s after 1 s of frames; path mode carries the line by the "
            "commands sent until it arrives (~use_odom:=false says that is intended)",
            odom_sub_.getTopic().c_str());
      }
    }
    if (law_->mode() != settings_.steering.mode) {
      NODELET_WARN_THROTTLE(5.0, "path mode: no valid camera_info on %s yet, steering with pd",
                            cameraInfoTopic().c_str());
    }
    return law_->step(
        {seen, stamp, has_odom_ ? odom_twist_ : last_command_, last_command_, measuredLatency()});
  }

  // The base's delay from its odometry (~estimate_latency), said when first measured and when
  // it moves by more than a frame at 30 Hz.
  std::optional<double> measuredLatency() {
    if (!settings_.estimate_latency || !has_odom_) return std::nullopt;
    const std::optional<double> latency = latency_.latency();
    if (latency && (!reported_latency_ || std::abs(*latency - *reported_latency_) > 0.033)) {
      reported_latency_ = latency;
      NODELET_INFO("path mode: the base's frame-to-motion delay measured on odom is %.3f s",
                   *latency);
    }
    return latency;
  }

  LineState state() const { return law_->state(); }

  // Once per configuration: which floor the bands look at on this camera, and loudly when a
  // distance asked for is outside what it sees.
  void reportPlacement(const BandMeasurement& band, const char* name, double wanted_m) {
    if (band.clamped) {
      NODELET_WARN(
          "%s: %.2f m ahead is outside the floor this camera sees (%.2f m up, pitched "
          "%.1f deg down); rows [%d, %d) instead, %.2f m ahead",
          name, wanted_m, camera().height_m, camera().pitch_rad * 180.0 / CV_PI, band.row_begin,
          band.row_end, band.distance_m);
    } else {
      NODELET_INFO("%s: rows [%d, %d), %.2f m ahead", name, band.row_begin, band.row_end,
                   band.distance_m);
    }
  }

  Decision step(const Frame& frame) override {
    // The last sighting keeps the band on the line it followed (see LineDetector::detect).
    seen_ = detector_->detect(frame.image, seen_);
    if (!placement_reported_) {
      placement_reported_ = true;
      reportPlacement(seen_.band, "~band_distance", settings_.detector.band.distance_m);
      if (settings_.detector.look_ahead_enabled) {
        reportPlacement(seen_.look_ahead, "~look_ahead_distance",
                        settings_.detector.look_ahead.distance_m);
      }
    }
    const Twist2D desired = steer(seen_, frame.time);
    if (!seen_.band.found)
      NODELET_WARN_THROTTLE(2.0, "no line in the band (%s)", toString(state()));
    // Idle once it has given up: any sighting makes it active again.
    return {desired, state() != LineState::kGaveUp, toString(state())};
  }

  void report(const Frame& frame, const Twist2D& sent) override {
    last_command_ = sent;
    latency_.commandSent(frame.time, sent);
    if (status_pub_.getNumSubscribers() > 0) {
      status_pub_.publish(lineStatus(frame.header, seen_, toString(state()), sent));
    }
  }

  void drawDebug(cv::Mat& canvas) override { detector_->drawDebug(canvas, seen_); }

  // The bands' line centres on the floor (where path mode places its sightings), path mode's
  // remembered line and the arc the last command drives over the next second.
  void addMarkers(RvizMarkers& markers) override {
    std::vector<cv::Point2d> sightings;
    for (const BandMeasurement* band : {&seen_.band, &seen_.look_ahead}) {
      if (!band->centre_found) continue;
      if (const std::optional<cv::Point2d> centre = floorCentre(*band, camera())) {
        sightings.push_back(*centre);
      }
    }
    markers.floorPoints("sightings", sightings, rgba(1.0, 0.5, 0.0), 0.05);
    if (const auto* path = dynamic_cast<const PathLaw*>(law_.get())) {
      markers.floorLine("path", path->pathPoints(), rgba(0.0, 0.8, 1.0), 0.02);
    }
    markers.floorLine("command_arc", predictedArc(last_command_, 1.0, 0.1), rgba(1.0, 0.0, 1.0),
                      0.01);
  }

  std::unique_ptr<LineDetector> detector_;
  std::unique_ptr<SteeringLaw> law_;
  FollowerSettings settings_;
  LineMeasurement seen_;  // the last frame's
  bool placement_reported_ = false;
  Twist2D last_command_;  // what the robot was told to do since the previous frame
  bool use_odom_ = FollowerStartupDefaults::use_odom;
  std::optional<double> first_path_stamp_;
  bool odom_absence_said_ = false;
  bool has_odom_ = false;
  Twist2D odom_twist_;
  LatencyEstimator latency_;
  std::optional<double> reported_latency_;
  ros::Subscriber odom_sub_;
  ros::Publisher status_pub_;
};

}  // namespace follow_bot

FOLLOW_BOT_EXPORT_NODELET(FollowerNodelet)

follow_bot_common::NodeHelp follow_bot::followerHelp() {
  return behaviourHelp(
      "Follows a coloured line on the floor (lecture, pd or path steering, ~mode).",
      {{"in", "odom", "nav_msgs/Odometry", "with ~use_odom (the default)"},
       {"out", "~line", "follow_bot/LineStatus", "centroid, error, confidence, state, command"},
       {"out", "~debug_image", "sensor_msgs/Image", "lazy: band, line pixels, centroid"},
       {"out", "~markers", "visualization_msgs/MarkerArray",
        "lazy, in ~base_frame: band sightings, remembered path, command arc"}});
}
