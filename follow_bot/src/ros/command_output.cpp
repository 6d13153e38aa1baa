#include "follow_bot/ros/command_output.h"

#include <algorithm>
#include <cmath>

#include <geometry_msgs/Twist.h>

#include "follow_bot/ros/params.h"
#include "image_converter/ros/frame_msg.h"

namespace follow_bot {

using image_converter::guardedCallback;

namespace {
VelocityLimiterConfig readLimits(const ros::NodeHandle& pnh, bool allow_reverse) {
  VelocityLimiterConfig config;
  config.allow_reverse = allow_reverse;
  config.max_linear = positiveParam(pnh, "limit_linear", config.max_linear);
  config.max_angular = positiveParam(pnh, "limit_angular", config.max_angular);
  config.max_linear_accel = positiveParam(pnh, "limit_linear_accel", config.max_linear_accel);
  config.max_angular_accel = positiveParam(pnh, "limit_angular_accel", config.max_angular_accel);
  return config;
}
}  // namespace

CommandOutput::CommandOutput(ros::NodeHandle& nh, ros::NodeHandle& pnh, bool allow_reverse)
    : limiter_(readLimits(pnh, allow_reverse)),
      watchdog_(positiveParam(pnh, "watchdog_timeout", 0.15)),
      wall_watchdog_(watchdog_.timeout()) {
  publisher_ = nh.advertise<geometry_msgs::Twist>("cmd_vel", 1);
  // Four checks per timeout bound the stop delay to 1.25 timeouts (on sim or wall time).
  timer_ =
      nh.createTimer(ros::Duration(watchdog_.timeout() / 4.0), &CommandOutput::checkWatchdog, this);
  wall_timer_ = nh.createSteadyTimer(ros::WallDuration(watchdog_.timeout() / 4.0),
                                     &CommandOutput::checkWallWatchdog, this);
}

CommandOutput::~CommandOutput() {
  timer_.stop();
  wall_timer_.stop();
  stop();
}

void CommandOutput::frameArrived() {
  ++frames_since_check_;
  ros_time_at_frame_ = ros::Time::now().toSec();
  watchdog_.frameArrived(ros_time_at_frame_);
  wall_watchdog_.frameArrived(ros::SteadyTime::now().toSec());
  outage_stopped_ = false;
}

Twist2D CommandOutput::send(const Twist2D& desired, const ros::Time& stamp) {
  // In double seconds: ros::Time's difference throws beyond 2^31 s, and stamps are input.
  // A gap longer than the watchdog timeout counts as the timeout: the robot cannot have been
  // moving longer than that on the last command, so acceleration stays bounded whatever the
  // stamps say (a backward stamp gives dt <= 0: the limiter then only slows down).
  const double dt = last_stamp_.isZero()
                        ? 0.0
                        : std::min(stamp.toSec() - last_stamp_.toSec(), watchdog_.timeout());
  last_stamp_ = stamp;
  const Twist2D command = limiter_.limit(desired, dt);
  // A frame's work ends here: wall time spent on it (while a lockstep clock waits for this
  // answer) is not silence.
  wall_watchdog_.frameArrived(ros::SteadyTime::now().toSec());
  publish(command);
  return command;
}

void CommandOutput::stop() {
  last_stamp_ = ros::Time();
  publish(limiter_.stop());
}

void CommandOutput::publish(const Twist2D& command) {
  geometry_msgs::Twist msg;
  msg.linear.x = command.linear;
  msg.angular.z = command.angular;
  publisher_.publish(msg);
}

void CommandOutput::checkWatchdog(const ros::TimerEvent&) {
  guardedCallback("watchdog", [this] { checkWatchdogNow(); });
}

void CommandOutput::checkWatchdogNow() {
  const double now = ros::Time::now().toSec();
  // Frames handled since the last check prove the camera is alive whatever the clock says: under
  // load the /clock thread can lag the image callbacks, so frames get stamped with a stale time.
  if (frames_since_check_ > 0) watchdog_.frameArrived(now);
  frames_since_check_ = 0;
  if (watchdog_.shouldSendStop(now)) stopForOutage("ROS", watchdog_.lastFrame(), now);
}

void CommandOutput::checkWallWatchdog(const ros::SteadyTimerEvent&) {
  guardedCallback("wall watchdog", [this] {
    // A ROS clock that moved since the last frame is the ROS-time watchdog's to judge.
    if (ros::Time::now().toSec() != ros_time_at_frame_) return;
    const double now = ros::SteadyTime::now().toSec();
    if (wall_watchdog_.shouldSendStop(now)) stopForOutage("wall", wall_watchdog_.lastFrame(), now);
  });
}

void CommandOutput::stopForOutage(const char* clock, double since, double now) {
  if (outage_stopped_) return;
  outage_stopped_ = true;
  ROS_WARN(
      "no camera frame since t=%.3f s (now %.3f s %s time, timeout %.2f s): stopping the robot",
      since, now, clock, watchdog_.timeout());
  stop();
}

}  // namespace follow_bot
