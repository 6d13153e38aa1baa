#include "follow_bot_common/ros/command_output.h"

#include <algorithm>
#include <cmath>

#include <geometry_msgs/Twist.h>

#include "follow_bot_common/ros/camera_input.h"
#include "follow_bot_common/ros/config_mapping.h"
#include "follow_bot_common/ros/params.h"
#include "follow_bot_common/ros/publish_last.h"
#include "follow_bot_msgs/BehaviourStatus.h"

namespace follow_bot_common {

namespace {
using Defaults = follow_bot_common::CommandOutputDefaults;

geometry_msgs::Twist twistMsg(const Twist2D& command) {
  geometry_msgs::Twist msg;
  msg.linear.x = command.linear;
  msg.angular.z = command.angular;
  return msg;
}

VelocityLimiterConfig readLimits(const ros::NodeHandle& pnh, bool allow_reverse) {
  VelocityLimiterConfig config;
  config.allow_reverse = allow_reverse;
  readFieldParams(pnh, config);
  return config;
}

// ~expected_frame_rate: 0 (the default) when the camera's rate is unknown.
double readExpectedFrameRate(const ros::NodeHandle& pnh) {
  return checkedParam(
      pnh, "expected_frame_rate", Defaults::expected_frame_rate,
      [](double v) { return std::isfinite(v) && v >= 0.0; }, ">= 0 (0: unknown)");
}

double periodOf(double rate) { return rate > 0.0 ? 1.0 / rate : 0.0; }
}  // namespace

CommandOutput::CommandOutput(ros::NodeHandle& nh, ros::NodeHandle& pnh, bool allow_reverse)
    : limiter_(readLimits(pnh, allow_reverse)),
      expected_rate_(readExpectedFrameRate(pnh)),
      watchdog_(positiveParam(pnh, "watchdog_timeout", Defaults::watchdog_timeout),
                periodOf(expected_rate_)),
      wall_watchdog_(positiveParam(pnh, "wall_watchdog_timeout", Defaults::wall_watchdog_timeout),
                     periodOf(expected_rate_)),
      updater_(nh, pnh, pnh.getNamespace()) {
  publisher_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
  // A queue: a lockstep simulator must see every frame's answer.
  status_pub_ = pnh.advertise<follow_bot_msgs::BehaviourStatus>("status", 10);
  enable_srv_ = pnh.advertiseService("enable", &CommandOutput::onEnable, this);
  noteParamRead(pnh, "diagnostic_period");  // read by updater_
  updater_.setHardwareID("none");
  updater_.add("frame rate", this, &CommandOutput::reportFrameRate);
  updater_.add("behaviour", this, &CommandOutput::reportStatus);
  // Four checks per (shortest) timeout bound the stop delay to 1.25 timeouts (on sim or wall
  // time).
  timer_ = nh.createTimer(ros::Duration(watchdog_.minTimeout() / 4.0),
                          &CommandOutput::checkWatchdog, this);
  wall_timer_ = nh.createSteadyTimer(ros::WallDuration(wall_watchdog_.minTimeout() / 4.0),
                                     &CommandOutput::checkWallWatchdog, this);
}

CommandOutput::~CommandOutput() {
  timer_.stop();
  wall_timer_.stop();
  std::lock_guard<std::mutex> lock(mutex_);
  last_stamp_ = ros::Time();
  publishLast(publisher_, twistMsg(limiter_.stop()));  // the final zero, always
}

ros::Time CommandOutput::frameTime(const std_msgs::Header& header) {
  return header.stamp.isZero() ? ros::Time::now() : header.stamp;
}

void CommandOutput::frameArrived() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frames_since_check_;
  watchdog_.frameArrived(ros::Time::now().toSec());
  wall_watchdog_.frameArrived(ros::SteadyTime::now().toSec());
  outage_stopped_ = false;
  stopped_by_watchdog_ = false;
  frames_seen_ = true;
}

void CommandOutput::frameHandled(FrameOutcome outcome, const std::string& error) {
  std::lock_guard<std::mutex> lock(mutex_);
  counts_.countFrame(outcome);
  if (outcome == FrameOutcome::kAccepted) return;
  ++dropped_since_report_;
  last_drop_ = error;
}

void CommandOutput::cameraInfoHandled(bool usable) {
  std::lock_guard<std::mutex> lock(mutex_);
  counts_.countCameraInfo(usable);
}

void CommandOutput::reportFrameRate(diagnostic_updater::DiagnosticStatusWrapper& status) {
  CameraHealth health;
  health.frames_seen = frames_seen_;
  // A stopped /clock holds ROS time: then only the wall watchdog's outage tells.
  health.frames_flowing = !outage_stopped_ && !watchdog_.expired(ros::Time::now().toSec());
  health.stopped_by_watchdog = stopped_by_watchdog_;
  health.interval = watchdog_.frameInterval();
  health.expected_rate = expected_rate_;
  health.timeout = watchdog_.timeout();
  const StatusReport report = frameRateStatus(health);
  status.summary(static_cast<unsigned char>(report.level), report.message);
  for (const auto& [key, value] : report.values) status.add(key, value);
}

void CommandOutput::reportStatus(diagnostic_updater::DiagnosticStatusWrapper& status) {
  if (stopped_by_watchdog_) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::ERROR,
                    "stopped by the watchdog: no camera frame for %.2f s (%s time)",
                    last_stop_timeout_, last_stop_clock_.c_str());
  } else if (outage_stopped_) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN,
                   "no frames, idle: nothing to stop (" + state_ + ")");
  } else if (dropped_since_report_ > 0) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%ld frames dropped since last report",
                    dropped_since_report_);
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "running");
  }
  dropped_since_report_ = 0;
  status.add("state", state_);
  status.add("enabled", enabled_);
  status.add("cmd_vel", quiet_ ? "quiet (stopped)" : "driving");
  for (const auto& [key, count] : counts_.frameValues()) status.add(key, count);
  for (const auto& [key, count] : counts_.cameraInfoValues()) status.add(key, count);
  status.add("last dropped frame", last_drop_);
  status.add("watchdog stops", watchdog_stops_);
  status.add("last watchdog stop clock", last_stop_clock_);
  status.add("watchdog timeout (s)", watchdog_.timeout());
  status.add("wall watchdog timeout (s)", wall_watchdog_.timeout());
}

Twist2D CommandOutput::send(const std_msgs::Header& frame, const Twist2D& desired, bool active,
                            const std::string& state, bool halt) {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::Time stamp = frameTime(frame);
  // In double seconds: ros::Time's difference throws beyond 2^31 s, and stamps are input.
  // A gap longer than the watchdog timeout in force (the camera's rate sets it) counts as the
  // timeout: the robot cannot have been moving longer than that on the last command, so
  // acceleration stays bounded whatever the stamps say (a backward stamp gives dt <= 0: the
  // limiter then only slows down).
  const double dt = last_stamp_.isZero()
                        ? 0.0
                        : std::min(stamp.toSec() - last_stamp_.toSec(), watchdog_.timeout());
  last_stamp_ = stamp;
  // The limiter runs on every frame, idle or not, so an active behaviour's commands are the
  // same whatever came before; disabled, it holds zero.
  const bool steering = enabled_ && active && !halt;
  const Twist2D command =
      halt ? limiter_.stop() : limiter_.limit(enabled_ ? desired : Twist2D{}, dt);
  const bool zero = command.linear == 0.0 && command.angular == 0.0;
  // Idle: finish the ramp down and send its one zero, then stay off cmd_vel.
  const bool sent = steering || !zero || !quiet_;
  if (sent) {
    publish(command);
    quiet_ = zero && !steering;
  }
  // A frame's work ends here: wall time spent on it (while a lockstep clock waits for this
  // answer) is not silence.
  wall_watchdog_.aliveAt(ros::SteadyTime::now().toSec());
  state_ = enabled_ ? state : "disabled (" + state + ")";

  follow_bot_msgs::BehaviourStatus status;
  status.header = frame;
  status.state = state;
  status.enabled = enabled_;
  status.active = steering;
  status.command_sent = sent;
  if (sent) {
    status.command.linear.x = command.linear;
    status.command.angular.z = command.angular;
  }
  status_pub_.publish(status);
  return command;
}

void CommandOutput::stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!quiet_) stopLocked();
}

void CommandOutput::stopLocked() {
  last_stamp_ = ros::Time();
  publish(limiter_.stop());
  quiet_ = true;
}

bool CommandOutput::onEnable(std_srvs::SetBool::Request& request,
                             std_srvs::SetBool::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!request.data && enabled_) stopLocked();  // the one zero, at once
  enabled_ = request.data;
  response.success = true;
  response.message = enabled_ ? "enabled" : "disabled: stopped, cmd_vel quiet";
  ROS_INFO("%s", response.message.c_str());
  return true;
}

void CommandOutput::publish(const Twist2D& command) { publisher_.publish(twistMsg(command)); }

void CommandOutput::checkWatchdog(const ros::TimerEvent& /*event*/) {
  guardedCallback("watchdog", [this] { checkWatchdogNow(); });
}

void CommandOutput::checkWatchdogNow() {
  std::lock_guard<std::mutex> lock(mutex_);
  const double now = ros::Time::now().toSec();
  // Frames handled since the last check prove the camera is alive whatever the clock says: under
  // load the /clock thread can lag the image callbacks, so frames get stamped with a stale time.
  // They arrived within the last check period, so no earlier than now - period: that keeps the
  // stop within 1.25 timeouts of the last frame instead of one period later.
  const double period = watchdog_.minTimeout() / 4.0;
  if (frames_since_check_ > 0) {
    watchdog_.aliveAt(std::max(watchdog_.lastFrame(), now - period));
  }
  frames_since_check_ = 0;
  if (watchdog_.shouldSendStop(now)) stopForOutage("ROS", watchdog_, now);
  updater_.update();
}

void CommandOutput::checkWallWatchdog(const ros::SteadyTimerEvent& /*event*/) {
  guardedCallback("wall watchdog", [this] {
    std::lock_guard<std::mutex> lock(mutex_);
    const double ros_now = ros::Time::now().toSec();
    const double now = ros::SteadyTime::now().toSec();
    if (ros_now != ros_time_seen_) {  // a running ROS clock is the ROS-time watchdog's to judge
      ros_time_seen_ = ros_now;
      ros_time_moved_at_ = now;
      return;
    }
    if (now - ros_time_moved_at_ <= wall_watchdog_.timeout()) return;
    if (wall_watchdog_.shouldSendStop(now)) stopForOutage("wall", wall_watchdog_, now);
  });
}

void CommandOutput::stopForOutage(const char* clock, const FrameWatchdog& watchdog, double now) {
  if (outage_stopped_) return;
  outage_stopped_ = true;
  if (quiet_) return;  // already stopped (idle or disabled): nothing to take back
  stopped_by_watchdog_ = true;
  ++watchdog_stops_;
  last_stop_clock_ = clock;
  last_stop_timeout_ = watchdog.timeout();
  ROS_WARN(
      "no camera frame since t=%.3f s (now %.3f s %s time, timeout %.2f s): stopping the robot",
      watchdog.lastFrame(), now, clock, watchdog.timeout());
  stopLocked();
  updater_.force_update();  // say why at once (a stopped /clock would hold back update())
}

}  // namespace follow_bot_common
