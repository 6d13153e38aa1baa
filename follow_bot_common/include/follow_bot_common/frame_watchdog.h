// Detects a stalled camera so a node can stop the robot instead of repeating a stale command.
#pragma once

#include <deque>

namespace follow_bot_common {

// Tracks the arrival time of camera frames. Times are seconds on any one clock (wall or sim
// time); pass the receipt time from the same clock as `now`, not the camera's header stamp, so
// clock skew between machines cannot fake an outage.
//
// The timeout follows the camera's rate: kPeriods times the median of the last kWindow
// intervals between frames, never less than the minimum timeout. A 30 Hz camera keeps the
// minimum; a 5 Hz one gets 0.6 s, so the gap between two of its frames is no outage. The median
// ignores a single long gap (a real outage), so it takes a lasting slowdown (half the window) to
// lengthen the timeout. Until an interval is measured the camera's expected frame period, when
// known, stands in for it.
//
// Typical use on a timer tick:
//   if (watchdog.shouldSendStop(now)) publish(limiter.stop());  // once per outage
//   if (watchdog.expired(now)) return;                         // then stay silent
class FrameWatchdog {
 public:
  static constexpr double kPeriods =
      3.0;                           // frame periods in the timeout: one lost frame is no outage
  static constexpr int kWindow = 9;  // intervals in the median

  // Throws std::invalid_argument unless min_timeout_s is finite and > 0 and expected_period_s is
  // finite and >= 0 (0: unknown).
  explicit FrameWatchdog(double min_timeout_s, double expected_period_s = 0.0);

  // Records a frame received at time t (non-finite t is ignored) and measures the interval since
  // the previous one (a clock running backwards measures none). Ends any outage.
  void frameArrived(double t);
  // Proof at time t that the camera is alive without a new frame (the work on the last frame
  // ended then, or frames were seen on another clock): ends any outage, measures no interval.
  void aliveAt(double t);

  // True when no frame arrived within the timeout before `now`: also before the first frame,
  // for a non-finite `now`, and when the clock jumped back before the last frame (a sim reset),
  // since the age of the last frame is then unknown.
  bool expired(double now) const;

  // True exactly once per outage: on the first call that finds the watchdog expired after at
  // least one frame had arrived. Before any frame nothing has been commanded, so no stop is due.
  bool shouldSendStop(double now);

  // Back to the initial state: no frame seen, no interval measured, no outage in progress.
  void reset();

  // The timeout in force: max(minimum, kPeriods x frameInterval(), or the expected period
  // before an interval is measured).
  double timeout() const;
  double minTimeout() const { return min_timeout_s_; }
  // The median of the last kWindow intervals between frames; 0 before two frames.
  double frameInterval() const { return interval_; }
  // Arrival time of the last frame (meaningless before the first).
  double lastFrame() const { return last_frame_; }

 private:
  double min_timeout_s_;
  double expected_period_s_;
  bool has_frame_ = false;
  double last_frame_ = 0.0;    // the last frame or proof of life
  double last_arrival_ = 0.0;  // the last frame: intervals are measured from it
  std::deque<double> intervals_;
  double interval_ = 0.0;  // median of intervals_, updated with them; 0 while none
  bool stop_sent_ = false;
};

}  // namespace follow_bot_common
