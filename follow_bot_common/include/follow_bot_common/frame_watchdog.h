// Detects a stalled camera so a node can stop the robot instead of repeating a stale command.
#pragma once

namespace follow_bot {

// Tracks the arrival time of camera frames. Times are seconds on any one clock (wall or sim
// time); pass the receipt time from the same clock as `now`, not the camera's header stamp, so
// clock skew between machines cannot fake an outage.
//
// Typical use on a timer tick:
//   if (watchdog.shouldSendStop(now)) publish(limiter.stop());  // once per outage
//   if (watchdog.expired(now)) return;                         // then stay silent
class FrameWatchdog {
 public:
  // Throws std::invalid_argument unless timeout_s is finite and > 0.
  explicit FrameWatchdog(double timeout_s);

  // Records a frame received at time t (non-finite t is ignored). Ends any outage.
  void frameArrived(double t);

  // True when no frame arrived within the timeout before `now`: also before the first frame,
  // for a non-finite `now`, and when the clock jumped back before the last frame (a sim reset),
  // since the age of the last frame is then unknown.
  bool expired(double now) const;

  // True exactly once per outage: on the first call that finds the watchdog expired after at
  // least one frame had arrived. Before any frame nothing has been commanded, so no stop is due.
  bool shouldSendStop(double now);

  // Back to the initial state: no frame seen, no outage in progress.
  void reset();

  double timeout() const { return timeout_s_; }
  // Arrival time of the last frame (meaningless before the first).
  double lastFrame() const { return last_frame_; }

 private:
  double timeout_s_;
  bool has_frame_ = false;
  double last_frame_ = 0.0;
  bool stop_sent_ = false;
};

}  // namespace follow_bot
