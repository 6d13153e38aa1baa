#include "follow_bot/panorama_capture.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace follow_bot {
namespace {
constexpr double kPi = 3.141592653589793;
}  // namespace

std::string validate(const PanoramaCaptureConfig& config) {
  if (!(config.total_angle > 0.0 && config.total_angle < 2.0 * kPi)) {
    return "total_angle must be in (0, 2 pi) rad";
  }
  if (!(config.step_angle > 0.0 && config.step_angle <= config.total_angle)) {
    return "step_angle must be in (0, total_angle] rad";
  }
  if (std::string error = checkFields(config); !error.empty()) return error;
  if (!(config.min_turn_rate > 0.0 && config.min_turn_rate <= config.max_turn_rate)) {
    return "min_turn_rate must be in (0, max_turn_rate] rad/s";
  }
  if (!(config.yaw_tolerance > 0.0 && config.yaw_tolerance < config.step_angle / 2.0)) {
    return "yaw_tolerance must be in (0, step_angle / 2) rad";
  }
  return "";
}

double wrapAngle(double angle) {
  const double wrapped = std::remainder(angle, 2.0 * kPi);
  return wrapped <= -kPi ? wrapped + 2.0 * kPi : wrapped;
}

double yawOfQuaternion(double x, double y, double z, double w) {
  const double norm2 = x * x + y * y + z * z + w * w;
  if (!(std::abs(norm2 - 1.0) < 2e-3)) return std::numeric_limits<double>::quiet_NaN();
  return std::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
}

PanoramaCapture::PanoramaCapture(const PanoramaCaptureConfig& config) : config_(config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("PanoramaCapture: " + error);
}

void PanoramaCapture::start(double start_yaw) {
  // Evenly spaced headings no further apart than step_angle, both ends of the sweep included.
  const int intervals =
      static_cast<int>(std::ceil(config_.total_angle / config_.step_angle - 1e-9));
  const double step = config_.total_angle / intervals;
  headings_.clear();
  for (int i = 0; i <= intervals; ++i) {
    headings_.push_back(wrapAngle(start_yaw + config_.total_angle / 2.0 - i * step));
  }
  start_yaw_ = start_yaw;
  next_heading_ = 0;
  still_frames_ = 0;
  active_ = true;
}

double PanoramaCapture::turnRateToward(double target, double yaw) const {
  const double error = wrapAngle(target - yaw);
  const double rate =
      std::clamp(config_.yaw_gain * std::abs(error), config_.min_turn_rate, config_.max_turn_rate);
  return std::copysign(rate, error);
}

PanoramaCapture::Step PanoramaCapture::update(double yaw) {
  Step step;
  if (!active_) return step;
  const bool returning = next_heading_ == headings_.size();
  const double target = returning ? start_yaw_ : headings_[next_heading_];
  if (std::abs(wrapAngle(target - yaw)) > config_.yaw_tolerance) {
    still_frames_ = 0;
    step.angular = turnRateToward(target, yaw);
    return step;
  }
  if (returning) {
    active_ = false;
    step.finished = true;
    return step;
  }
  // At the heading: hold still for settle_frames frames, then grab the next one.
  if (still_frames_++ < config_.settle_frames) return step;
  step.grab = true;
  still_frames_ = 0;
  ++next_heading_;
  if (next_heading_ == headings_.size() && !config_.return_to_start) {
    active_ = false;
    step.finished = true;
  }
  return step;
}

}  // namespace follow_bot
