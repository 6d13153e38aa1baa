// The one way a behaviour node commands the base: limits, active/idle, ~enable, the per-frame
// ~status, a frame watchdog and a final stop.
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <std_srvs/SetBool.h>

#include "follow_bot_common/frame_counts.h"
#include "follow_bot_common/frame_rate_status.h"
#include "follow_bot_common/frame_watchdog.h"
#include "follow_bot_common/velocity_limiter.h"

namespace follow_bot_common {

// Publishes geometry_msgs/Twist on `cmd_vel` through a VelocityLimiter while the behaviour is
// active (docs/behaviour_contract.md):
//  * send() once per processed frame, saying whether the behaviour steers (active) or not
//    (idle). Active: the limited command goes out. Idle: the limited command goes out until it
//    reaches zero (the limiter's ramp down, exactly as while active), that one zero included,
//    then nothing until the behaviour is active again. A node that starts idle sends nothing.
//    Halting (idle with `halt`): the zero goes out at once, past the deceleration bound.
//  * ~enable (std_srvs/SetBool): false publishes one zero at once and keeps the node idle
//    whatever it sees (the limiter ramps up from zero after true).
//  * ~status (follow_bot_msgs/BehaviourStatus): one per send(), stamped with the frame's stamp:
//    state, active, whether a command went out and which. The lockstep simulator waits for it.
// Two watchdogs, one zero Twist per outage between them (none when already stopped), then
// nothing until frames return; the destructor publishes a last zero and holds the publisher
// 0.1 s of wall time so that it leaves. Each watchdog's timeout follows the camera's rate
// (FrameWatchdog: 3 median frame intervals, the expected ~expected_frame_rate's until measured),
// never below its ~param, so a slow camera's gap between frames is no outage. The watchdogs:
//  * ROS time: no frame for the timeout (at least ~watchdog_timeout) of ROS time (sim time under
//    use_sim_time).
//  * Wall (steady) time: no frame for the timeout (at least ~wall_watchdog_timeout) of wall time
//    while ROS time has not
//    advanced for that long of wall time either. With use_sim_time, when /clock and the frames
//    stop together (the simulator or rosbag died), ROS time stands still and the first rule never
//    fires. A running ROS clock leaves the decision to the first rule (sim time may run at any
//    rate). A lockstep simulator holds /clock while it renders, so it sets this timeout above its
//    longest step: a slow step is not an outage.
//
// Diagnostics: two diagnostic_updater statuses per node on /diagnostics, every
// ~diagnostic_period. "<node>: frame rate" (frameRateStatus): the measured rate against
// ~expected_frame_rate (Hz; 0, the default, unknown: any rate is OK; else +-20 %), the
// watchdog's timeout in force. "<node>: behaviour": every frame and camera_info received,
// counted once under its outcome (FrameCounts: frames_accepted, dropped_bad_size, ...,
// camera_info_accepted, dropped_bad_camera_info), the last drop's reason, watchdog stops (and on
// which clock), the behaviour's state. Both are ERROR only while the watchdog has stopped the
// robot; frames stopping while nothing was commanded (idle, disabled) is a WARN saying so;
// dropped frames since the last report are a WARN.
//
// Parameters (private): ~limit_linear (m/s, 0.7), ~limit_angular (rad/s, pi),
// ~limit_linear_accel (m/s^2, 1.0), ~limit_angular_accel (rad/s^2, 6.0),
// ~watchdog_timeout (s, 0.15), ~wall_watchdog_timeout (s, 0.15), ~expected_frame_rate (Hz, 0:
// unknown). Invalid values throw
// std::invalid_argument. Negative linear commands are clamped to 0 unless `allow_reverse` (a
// behaviour that must back up, the parker).
class CommandOutput {
 public:
  CommandOutput(ros::NodeHandle& nh, ros::NodeHandle& pnh, bool allow_reverse = false);
  ~CommandOutput();
  CommandOutput(const CommandOutput&) = delete;
  CommandOutput& operator=(const CommandOutput&) = delete;

  // The time a frame stands for: its stamp, or now when it has none.
  static ros::Time frameTime(const std_msgs::Header& header);

  // Records that a usable frame arrived now.
  void frameArrived();
  // Counts one received frame under what became of it; `error` says why one was dropped.
  void frameHandled(FrameOutcome outcome, const std::string& error = "");
  // Counts one received camera_info, taken as the intrinsics (`usable`) or ignored.
  void cameraInfoHandled(bool usable);
  // One processed frame's decision. Limits `desired` (acceleration against the previous send,
  // frameTime(frame) being the frame's time), publishes it per the active/idle rules above and
  // publishes the frame's ~status; `state` names the behaviour's state (status, diagnostics);
  // `halt`: idle, and zero at once (VelocityLimiter::stop) rather than by the ramp down.
  // Returns the limited command: what the robot was told, or zero when quiet. Any stamps are
  // safe: the time since the previous send is taken as at most the watchdog's timeout, and as none
  // when it runs backwards.
  Twist2D send(const std_msgs::Header& frame, const Twist2D& desired, bool active,
               const std::string& state, bool halt = false);
  // Stops now: an immediate zero, unless already stopped (then nothing: cmd_vel stays quiet).
  void stop();

 private:
  void stopLocked();
  void publish(const Twist2D& command);
  bool onEnable(std_srvs::SetBool::Request& request, std_srvs::SetBool::Response& response);
  void checkWatchdog(const ros::TimerEvent& /*event*/);
  void checkWatchdogNow();
  void checkWallWatchdog(const ros::SteadyTimerEvent& /*event*/);
  void stopForOutage(const char* clock, const FrameWatchdog& watchdog, double now);
  void reportFrameRate(diagnostic_updater::DiagnosticStatusWrapper& status);
  void reportStatus(diagnostic_updater::DiagnosticStatusWrapper& status);

  std::mutex mutex_;  // frames, ~enable and the watchdog timers may run on different threads
  ros::Publisher publisher_;
  ros::Publisher status_pub_;
  ros::ServiceServer enable_srv_;
  bool enabled_ = true;
  bool quiet_ = true;  // the last command published (or none yet) is a zero: idle sends nothing
  ros::Timer timer_;
  ros::SteadyTimer wall_timer_;
  VelocityLimiter limiter_;
  double expected_rate_;              // Hz, 0: unknown
  FrameWatchdog watchdog_;            // on ROS time
  FrameWatchdog wall_watchdog_;       // on steady time
  double ros_time_seen_ = -1.0;       // ROS time at the last wall check
  double ros_time_moved_at_ = 0.0;    // steady time when it last changed
  bool outage_stopped_ = false;       // one stop per outage, whichever watchdog sees it first
  bool stopped_by_watchdog_ = false;  // this outage's stop went out: the robot was moving

  diagnostic_updater::Updater updater_;
  std::string state_ = "starting";
  bool frames_seen_ = false;  // a usable frame arrived
  FrameCounts counts_;
  std::string last_drop_;  // why the last dropped frame was dropped
  long dropped_since_report_ = 0;
  long watchdog_stops_ = 0;
  std::string last_stop_clock_ = "none";
  double last_stop_timeout_ = 0.0;  // of the watchdog that stopped the robot last
  ros::Time last_stamp_;
  int frames_since_check_ = 0;
};

}  // namespace follow_bot_common
