#include "follow_bot/line_controller.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "follow_bot/config_checks.h"

namespace follow_bot {
namespace {

// The lecture's constants.
constexpr double kLectureLinear = 0.2;              // m/s
constexpr double kLecturePixelsPerRadPerS = 100.0;  // angular = -error_px / 100

std::string requireAtMostMaxLinear(const char* name, double value, double max_linear) {
  if (value <= max_linear) return "";
  std::ostringstream message;
  message << name << " (" << value << ") must be <= max_linear (" << max_linear << ")";
  return message.str();
}

bool sees(const BandMeasurement& band, double min_confidence) {
  return band.found && band.confidence >= min_confidence && std::isfinite(band.error_normalised);
}

}  // namespace

std::optional<ControlMode> parseControlMode(const std::string& name) {
  if (name == "lecture") return ControlMode::kLecture;
  if (name == "pd") return ControlMode::kPD;
  return std::nullopt;
}

const char* toString(ControlMode mode) {
  switch (mode) {
    case ControlMode::kLecture:
      return "lecture";
    case ControlMode::kPD:
      return "pd";
  }
  return "unknown";
}

const char* toString(LineState state) {
  switch (state) {
    case LineState::kFollowing:
      return "FOLLOWING";
    case LineState::kLost:
      return "LOST";
    case LineState::kSearching:
      return "SEARCHING";
    case LineState::kGaveUp:
      return "GAVE_UP";
  }
  return "UNKNOWN";
}

std::string validate(const LineControllerConfig& c) {
  for (const std::string& error : {
           requireAtLeast("kp", c.kp, 0.0),
           requireAtLeast("kd", c.kd, 0.0),
           requirePositive("max_angular", c.max_angular),
           requirePositive("max_derivative_dt", c.max_derivative_dt),
           requireInRange("look_ahead_weight", c.look_ahead_weight, 0.0, 1.0),
           requireInRange("min_confidence", c.min_confidence, 0.0, 1.0),
           requirePositive("max_linear", c.max_linear),
           requireAtLeast("min_linear", c.min_linear, 0.0),
           requireAtMostMaxLinear("min_linear", c.min_linear, c.max_linear),
           requireAtLeast("taper", c.taper, 0.0),
           requireAtLeast("curvature_taper", c.curvature_taper, 0.0),
           requireAtLeast("lost_grace", c.lost_grace, 0.0),
           requireAtLeast("lost_linear", c.lost_linear, 0.0),
           requireAtMostMaxLinear("lost_linear", c.lost_linear, c.max_linear),
           requireAtLeast("lost_angular", c.lost_angular, 0.0),
           requireAtLeast("search_rate", c.search_rate, 0.0),
           requireAtLeast("search_timeout", c.search_timeout, 0.0),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

LineController::LineController(const LineControllerConfig& config) : config_(config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("LineController: " + error);
}

void LineController::reset() { *this = LineController(config_); }

Twist2D LineController::update(const LineMeasurement& measurement, double stamp) {
  if (config_.mode == ControlMode::kLecture) return updateLecture(measurement);
  if (!std::isfinite(stamp)) return Twist2D();
  if (has_stamp_ && stamp < last_stamp_) reset();
  if (!has_stamp_) outage_start_ = stamp;
  has_stamp_ = true;
  last_stamp_ = stamp;

  if (measurement.ok() && sees(measurement.band, config_.min_confidence)) {
    return follow(measurement, stamp);
  }
  return searchForLine(stamp);
}

Twist2D LineController::updateLecture(const LineMeasurement& measurement) {
  const BandMeasurement& band = measurement.band;
  if (!measurement.ok() || band.pixel_count == 0 || !std::isfinite(band.error_px)) {
    state_ = LineState::kLost;
    return Twist2D();
  }
  state_ = LineState::kFollowing;
  return Twist2D{kLectureLinear, -band.error_px / kLecturePixelsPerRadPerS};
}

Twist2D LineController::follow(const LineMeasurement& measurement, double stamp) {
  const double near_error = std::clamp(measurement.band.error_normalised, -1.0, 1.0);
  double error = near_error;
  double curvature = 0.0;
  if (sees(measurement.look_ahead, config_.min_confidence)) {
    const double ahead_error = std::clamp(measurement.look_ahead.error_normalised, -1.0, 1.0);
    error =
        (1.0 - config_.look_ahead_weight) * near_error + config_.look_ahead_weight * ahead_error;
    curvature = std::abs(ahead_error - near_error);
  }

  // Differentiate the near band only: the blend jumps whenever the look-ahead band comes and
  // goes, which would kick the derivative.
  double error_rate = 0.0;
  if (has_previous_error_) {
    const double dt = stamp - previous_error_stamp_;
    // A denormal dt can overflow the rate to inf, and 0 * inf would be NaN.
    const double rate = (near_error - previous_error_) / dt;
    if (dt > 0.0 && dt <= config_.max_derivative_dt && std::isfinite(rate)) error_rate = rate;
  }
  has_previous_error_ = true;
  previous_error_ = near_error;
  previous_error_stamp_ = stamp;

  if (near_error != 0.0) turn_direction_ = near_error > 0.0 ? -1.0 : 1.0;
  seen_once_ = true;
  outage_start_ = stamp;
  state_ = LineState::kFollowing;

  Twist2D command;
  command.angular = std::clamp(-(config_.kp * error + config_.kd * error_rate),
                               -config_.max_angular, config_.max_angular);
  command.linear = std::clamp(config_.max_linear * (1.0 - config_.taper * std::abs(error) -
                                                    config_.curvature_taper * curvature),
                              config_.min_linear, config_.max_linear);
  return command;
}

Twist2D LineController::searchForLine(double stamp) {
  has_previous_error_ = false;
  const double outage = stamp - outage_start_;
  if (seen_once_ && outage <= config_.lost_grace) {
    state_ = LineState::kLost;
    return Twist2D{config_.lost_linear, turn_direction_ * config_.lost_angular};
  }
  const double search_start = seen_once_ ? config_.lost_grace : 0.0;
  if (outage <= search_start + config_.search_timeout) {
    state_ = LineState::kSearching;
    return Twist2D{0.0, turn_direction_ * config_.search_rate};
  }
  state_ = LineState::kGaveUp;
  return Twist2D();
}

}  // namespace follow_bot
