// Measures a base's frame-to-motion delay: how long after a camera frame the command made from
// it shows in the base's odometry. Path mode steers from where the commands still in flight
// will take the robot (line_path.h); a fixed guess over-predicts on a base that acts at once
// and under-predicts on a slow one, and both cost millimetres on every curve.
//
// Each command is held from the stamp of the frame it was made from until the next one. An
// odometry twist is the base's mean motion since the previous odometry message. For each
// candidate delay d the odometry is compared with the commands' mean over the same span
// shifted back by d; the delay with the smallest squared difference, per channel (linear,
// angular) relative to that channel's variance over the window, is the estimate. A channel
// counts only while the base's motion varies in it (a ramp, a curve), since a constant motion
// fits every delay alike; the estimate is kept until a window explains at least
// 1 - max_unexplained of the motion's variance. A first-order motor lag of time constant T
// reads as a delay of about T more, which is where a ramp's commands take effect.
#pragma once

#include <deque>
#include <optional>
#include <string>

#include "follow_bot/common.h"
#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/velocity_limiter.h"

namespace follow_bot {

struct LatencyEstimatorConfig {
  double max_latency = 0.5;          // s, the longest delay tried (command_latency's range)
  double resolution = 0.005;         // s between the delays tried
  double window = 4.0;               // s of odometry each estimate compares
  double update_period = 0.25;       // s between estimates
  double min_linear_spread = 0.01;   // m/s, standard deviation for the linear channel to count
  double min_angular_spread = 0.05;  // rad/s, likewise for the angular channel
  double max_unexplained = 0.5;      // of the variance, for a window's estimate to be taken

  static constexpr auto fields() {
    using C = LatencyEstimatorConfig;
    return std::make_tuple(field("max_latency", &C::max_latency, positive()),
                           field("resolution", &C::resolution, positive()),
                           field("window", &C::window, positive()),
                           field("update_period", &C::update_period, atLeast(0.0)),
                           field("min_linear_spread", &C::min_linear_spread, positive()),
                           field("min_angular_spread", &C::min_angular_spread, positive()),
                           field("max_unexplained", &C::max_unexplained, inRange(0.0, 1.0)));
  }
};

// Empty when usable, else a message naming the first bad field.
std::string validate(const LatencyEstimatorConfig& config);

class LatencyEstimator {
 public:
  // Throws std::invalid_argument with the validate() message.
  explicit LatencyEstimator(const LatencyEstimatorConfig& config = {});

  // The command sent for the frame stamped `stamp` (s), held until the next one. Before the
  // first, a base whose odometry reads exactly zero motion is taken to have been told to stand
  // still. An earlier stamp than the last (a bag or simulation restarting) forgets everything
  // first; non-finite values are ignored.
  void commandSent(double stamp, const Twist2D& command);
  // The base's odometry twist stamped `stamp` (s), on the same clock as the frames.
  void measured(double stamp, const Twist2D& twist);

  // s, the latest estimate; empty until the commands have varied enough to tell.
  std::optional<double> latency() const { return latency_; }
  void reset();

 private:
  struct Command {
    double stamp;
    Twist2D twist;
    Twist2D integral;  // of the commands from the first one kept up to `stamp`
  };
  struct Odometry {
    double stamp;
    double span;  // s it averages over, 0 for the first message
    Twist2D twist;
  };

  // The command held at t; t must not precede the first command kept.
  const Command& heldAt(double t) const;
  // Integral of the held commands up to t; t must not precede the first command kept.
  Twist2D integralAt(double t) const;
  // The commands' mean over [t - span, t] (their value at t when span is 0).
  Twist2D meanOver(double t, double span) const;
  void estimate();
  void forgetBefore(double stamp);

  LatencyEstimatorConfig config_;
  std::deque<Command> commands_;  // oldest first
  std::deque<Odometry> odometry_;
  std::optional<double> latency_;
  double last_update_ = 0.0;
};

}  // namespace follow_bot
