#include "follow_bot/latency_estimator.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <vector>

#include "follow_bot/common.h"

namespace follow_bot {
namespace {

// Odometry messages further apart than this are compared at their stamp only: a gap is not a
// span the base moved evenly over.
constexpr double kMaxOdometrySpan = 0.2;  // s

bool isFinite(const Twist2D& twist) {
  return std::isfinite(twist.linear) && std::isfinite(twist.angular);
}

bool isAtRest(const Twist2D& twist) { return twist.linear == 0.0 && twist.angular == 0.0; }

}  // namespace

std::string validate(const LatencyEstimatorConfig& config) { return checkFields(config); }

LatencyEstimator::LatencyEstimator(const LatencyEstimatorConfig& config) : config_(config) {
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument(error);
}

void LatencyEstimator::reset() {
  commands_.clear();
  odometry_.clear();
  latency_.reset();
  last_update_ = 0.0;
}

void LatencyEstimator::commandSent(double stamp, const Twist2D& command) {
  if (!std::isfinite(stamp) || !isFinite(command)) return;
  if (!commands_.empty() && stamp < commands_.back().stamp) reset();
  if (commands_.empty() && !odometry_.empty() && isAtRest(odometry_.back().twist)) {
    // A base at rest before the first command was told nothing: its start from rest, the
    // clearest change of motion there is, can then be measured at once.
    commands_.push_back(
        Command{stamp - config_.window - config_.max_latency - kMaxOdometrySpan, {}, {}});
  }
  Twist2D integral;
  if (!commands_.empty()) integral = integralAt(stamp);
  commands_.push_back(Command{stamp, command, integral});
  forgetBefore(stamp);
  if (stamp - last_update_ >= config_.update_period) {
    last_update_ = stamp;
    estimate();
  }
}

void LatencyEstimator::measured(double stamp, const Twist2D& twist) {
  if (!std::isfinite(stamp) || !isFinite(twist)) return;
  if (!odometry_.empty() && stamp <= odometry_.back().stamp) {
    if (stamp < odometry_.back().stamp)
      odometry_.clear();
    else
      return;  // a repeat
  }
  const double span = odometry_.empty() ? 0.0 : stamp - odometry_.back().stamp;
  odometry_.push_back(Odometry{stamp, span <= kMaxOdometrySpan ? span : 0.0, twist});
}

const LatencyEstimator::Command& LatencyEstimator::heldAt(double t) const {
  const auto after = std::upper_bound(commands_.begin(), commands_.end(), t,
                                      [](double time, const Command& c) { return time < c.stamp; });
  return *std::prev(after);
}

Twist2D LatencyEstimator::integralAt(double t) const {
  const Command& held = heldAt(t);
  const double dt = t - held.stamp;
  return {held.integral.linear + held.twist.linear * dt,
          held.integral.angular + held.twist.angular * dt};
}

Twist2D LatencyEstimator::meanOver(double t, double span) const {
  if (span <= 0.0) return heldAt(t).twist;
  const Twist2D end = integralAt(t);
  const Twist2D begin = integralAt(t - span);
  return {(end.linear - begin.linear) / span, (end.angular - begin.angular) / span};
}

void LatencyEstimator::forgetBefore(double stamp) {
  // Commands back to the oldest odometry kept, less the longest delay and span, stay.
  const double keep_from = stamp - config_.window - config_.max_latency - kMaxOdometrySpan;
  while (!odometry_.empty() && odometry_.front().stamp < stamp - config_.window) {
    odometry_.pop_front();
  }
  while (commands_.size() > 1 && commands_[1].stamp <= keep_from) commands_.pop_front();
}

void LatencyEstimator::estimate() {
  // The odometry whose every shifted span lies within the commands known: after the first by
  // the longest delay, and not after the latest command (later ones may still change).
  const double first = commands_.front().stamp;
  const double last = commands_.back().stamp;
  std::vector<const Odometry*> samples;
  for (const Odometry& odometry : odometry_) {
    if (odometry.stamp - odometry.span - config_.max_latency >= first && odometry.stamp <= last) {
      samples.push_back(&odometry);
    }
  }
  if (samples.size() < 2) return;

  // Each channel counts only where the base's motion varied.
  double mean_linear = 0.0, mean_angular = 0.0;
  for (const Odometry* odometry : samples) {
    mean_linear += odometry->twist.linear;
    mean_angular += odometry->twist.angular;
  }
  const double n = static_cast<double>(samples.size());
  mean_linear /= n;
  mean_angular /= n;
  double var_linear = 0.0, var_angular = 0.0;
  for (const Odometry* odometry : samples) {
    var_linear += std::pow(odometry->twist.linear - mean_linear, 2);
    var_angular += std::pow(odometry->twist.angular - mean_angular, 2);
  }
  var_linear /= n;
  var_angular /= n;
  const bool use_linear = var_linear >= std::pow(config_.min_linear_spread, 2);
  const bool use_angular = var_angular >= std::pow(config_.min_angular_spread, 2);
  if (!use_linear && !use_angular) return;

  double best_cost = std::numeric_limits<double>::infinity();
  double best_delay = 0.0;
  const int steps = static_cast<int>(std::floor(config_.max_latency / config_.resolution + 1e-9));
  for (int step = 0; step <= steps; ++step) {
    const double delay = step * config_.resolution;
    double linear_error = 0.0, angular_error = 0.0;
    for (const Odometry* odometry : samples) {
      const Twist2D commanded = meanOver(odometry->stamp - delay, odometry->span);
      linear_error += std::pow(odometry->twist.linear - commanded.linear, 2);
      angular_error += std::pow(odometry->twist.angular - commanded.angular, 2);
    }
    // The fraction of each channel's variance left unexplained, averaged over those that count.
    const double cost = ((use_linear ? linear_error / (n * var_linear) : 0.0) +
                         (use_angular ? angular_error / (n * var_angular) : 0.0)) /
                        ((use_linear ? 1.0 : 0.0) + (use_angular ? 1.0 : 0.0));
    if (cost < best_cost) {
      best_cost = cost;
      best_delay = delay;
    }
  }
  if (best_cost <= config_.max_unexplained) latency_ = best_delay;
}

}  // namespace follow_bot
