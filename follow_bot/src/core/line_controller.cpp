#include "follow_bot/line_controller.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace follow_bot {
namespace {

// The lecture's constants.
constexpr double kLectureLinear = 0.2;              // m/s
constexpr double kLecturePixelsPerRadPerS = 100.0;  // angular = -error_px / 100

bool sees(const BandMeasurement& band, double min_confidence) {
  return band.found && band.confidence >= min_confidence && std::isfinite(band.error_normalised);
}

const SteeringConfig& validated(const SteeringConfig& config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument("PdLaw: " + error);
  return config;
}

}  // namespace

void LineSearch::seen(double stamp, double error) {
  if (error != 0.0) turn_direction_ = error > 0.0 ? -1.0 : 1.0;
  seen_once_ = true;
  timing_ = true;
  outage_start_ = stamp;
  state_ = LineState::kFollowing;
}

Twist2D LineSearch::unseen(double stamp) {
  if (!timing_) {
    timing_ = true;
    outage_start_ = stamp;
  }
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

Twist2D LectureLaw::step(const LineObservation& frame) {
  const BandMeasurement& band = frame.measurement.band;
  if (!frame.measurement.ok() || band.pixel_count == 0 || !std::isfinite(band.error_px)) {
    state_ = LineState::kLost;
    return Twist2D();
  }
  state_ = LineState::kFollowing;
  return Twist2D{kLectureLinear, -band.error_px / kLecturePixelsPerRadPerS};
}

PdLaw::PdLaw(const SteeringConfig& config) : config_(validated(config)), search_(config.search) {}

void PdLaw::reset() { *this = PdLaw(config_); }

Twist2D PdLaw::step(const LineObservation& frame) {
  const double stamp = frame.stamp;
  if (!std::isfinite(stamp)) return Twist2D();
  if (has_stamp_ && stamp < last_stamp_) reset();
  has_stamp_ = true;
  last_stamp_ = stamp;

  if (frame.measurement.ok() && sees(frame.measurement.band, config_.min_confidence)) {
    return follow(frame.measurement, stamp);
  }
  has_previous_error_ = false;
  return search_.unseen(stamp);
}

Twist2D PdLaw::follow(const LineMeasurement& measurement, double stamp) {
  const PdConfig& pd = config_.pd;
  const double near_error = std::clamp(measurement.band.error_normalised, -1.0, 1.0);
  double error = near_error;
  double curvature = 0.0;
  if (sees(measurement.look_ahead, config_.min_confidence)) {
    const double ahead_error = std::clamp(measurement.look_ahead.error_normalised, -1.0, 1.0);
    error = (1.0 - pd.look_ahead_weight) * near_error + pd.look_ahead_weight * ahead_error;
    curvature = std::abs(ahead_error - near_error);
  }

  // Differentiate the near band only: the blend jumps whenever the look-ahead band comes and
  // goes, which would kick the derivative.
  double error_rate = 0.0;
  if (has_previous_error_) {
    const double dt = stamp - previous_error_stamp_;
    // A denormal dt can overflow the rate to inf, and 0 * inf would be NaN.
    const double rate = (near_error - previous_error_) / dt;
    if (dt > 0.0 && dt <= pd.max_derivative_dt && std::isfinite(rate)) error_rate = rate;
  }
  has_previous_error_ = true;
  previous_error_ = near_error;
  previous_error_stamp_ = stamp;
  search_.seen(stamp, near_error);

  Twist2D command;
  command.angular =
      std::clamp(-(pd.kp * error + pd.kd * error_rate), -config_.max_angular, config_.max_angular);
  command.linear = std::clamp(
      config_.max_linear * (1.0 - pd.taper * std::abs(error) - pd.curvature_taper * curvature),
      config_.min_linear, config_.max_linear);
  return command;
}

}  // namespace follow_bot
