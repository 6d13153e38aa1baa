// The last line of defence before /cmd_vel: every behaviour node sends its command through a
// VelocityLimiter, which bounds speed and acceleration and never lets a NaN reach the base.
#pragma once

#include <string>

#include "follow_bot_common/CommandOutputDefaults.h"
#include "follow_bot_common/config_fields.h"

namespace follow_bot_common {

// A planar velocity command in the robot frame (REP-103): linear along +x (forward) in m/s,
// angular about +z in rad/s, positive = counter-clockwise = turning left.
struct Twist2D {
  double linear = 0.0;
  double angular = 0.0;
};

// Defaults: CommandOutput's ~limit_* (cfg/CommandOutput.cfg).
struct VelocityLimiterConfig {
  // m/s and rad/s, magnitude bounds on linear and angular.
  double max_linear = follow_bot_common::CommandOutputDefaults::limit_linear;
  double max_angular = follow_bot_common::CommandOutputDefaults::limit_angular;
  // m/s^2 and rad/s^2, bounds on |change of linear| and |change of angular| per second.
  double max_linear_accel = follow_bot_common::CommandOutputDefaults::limit_linear_accel;
  double max_angular_accel = follow_bot_common::CommandOutputDefaults::limit_angular_accel;
  bool allow_reverse = false;  // when false, negative linear is clamped to 0

  // The limits are CommandOutput's ~limit_* start-up parameters; allow_reverse is the behaviour's.
  static constexpr auto fields() {
    using C = VelocityLimiterConfig;
    return std::make_tuple(
        cfgField("max_linear", &C::max_linear, positive(), "limit_linear"),
        cfgField("max_angular", &C::max_angular, positive(), "limit_angular"),
        cfgField("max_linear_accel", &C::max_linear_accel, positive(), "limit_linear_accel"),
        cfgField("max_angular_accel", &C::max_angular_accel, positive(), "limit_angular_accel"),
        field("allow_reverse", &C::allow_reverse));
  }
};

// Empty when the configuration is usable, otherwise a message naming the first bad field.
std::string validate(const VelocityLimiterConfig& config);

// Clamps and rate-limits velocity commands.
//
// Safety rules, in order:
//  * a non-finite component of the desired command is replaced by 0;
//  * magnitudes are clamped to max_linear / max_angular (and linear to >= 0 unless
//    allow_reverse);
//  * each component may change from the previous output by at most accel * dt;
//  * without a usable dt (dt <= 0 or non-finite) no time is known to have passed, so a component
//    may only move toward zero (slow down), never speed up;
//  * before the first command and after reset() or stop() the previous output is taken as zero
//    (robot at rest), so motion always ramps up from standstill.
// stop() is the exception to the rate limit: it returns zero at once, because a stop is a
// safety action and must not be delayed by the deceleration bound.
class VelocityLimiter {
 public:
  // Throws std::invalid_argument with the validate() message when the configuration is unusable.
  explicit VelocityLimiter(const VelocityLimiterConfig& config = VelocityLimiterConfig());

  // The command to send, given the desired one and the seconds since the previous limit() call.
  Twist2D limit(const Twist2D& desired, double dt);

  // Immediate zero command; the next limit() ramps up from rest.
  Twist2D stop();

  // Forgets the previous output (assumes the robot is at rest), e.g. when a node is re-enabled.
  void reset();

  const Twist2D& lastOutput() const { return last_; }
  const VelocityLimiterConfig& config() const { return config_; }

 private:
  VelocityLimiterConfig config_;
  Twist2D last_;
};

}  // namespace follow_bot_common
