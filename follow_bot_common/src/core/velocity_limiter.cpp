#include "follow_bot_common/velocity_limiter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace follow_bot_common {
namespace {

double finiteOrZero(double value) { return std::isfinite(value) ? value : 0.0; }

// Moves `previous` toward `target` by at most `max_step`.
double stepToward(double previous, double target, double max_step) {
  return std::clamp(target, previous - max_step, previous + max_step);
}

// Without elapsed time only deceleration is safe: the result lies between 0 and `previous`.
double slowDownOnly(double previous, double target) {
  return std::clamp(target, std::min(previous, 0.0), std::max(previous, 0.0));
}

}  // namespace

std::string validate(const VelocityLimiterConfig& config) { return checkFields(config); }

VelocityLimiter::VelocityLimiter(const VelocityLimiterConfig& config) : config_(config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("VelocityLimiter: " + error);
}

Twist2D VelocityLimiter::limit(const Twist2D& desired, double dt) {
  const double min_linear = config_.allow_reverse ? -config_.max_linear : 0.0;
  Twist2D target;
  target.linear = std::clamp(finiteOrZero(desired.linear), min_linear, config_.max_linear);
  target.angular =
      std::clamp(finiteOrZero(desired.angular), -config_.max_angular, config_.max_angular);

  Twist2D output;
  if (std::isfinite(dt) && dt > 0.0) {
    // With a huge dt the product may be inf; clamp then simply returns the target.
    output.linear = stepToward(last_.linear, target.linear, config_.max_linear_accel * dt);
    output.angular = stepToward(last_.angular, target.angular, config_.max_angular_accel * dt);
  } else {
    output.linear = slowDownOnly(last_.linear, target.linear);
    output.angular = slowDownOnly(last_.angular, target.angular);
  }
  last_ = output;
  return output;
}

Twist2D VelocityLimiter::stop() {
  last_ = Twist2D();
  return last_;
}

void VelocityLimiter::reset() { last_ = Twist2D(); }

}  // namespace follow_bot_common
