#include "follow_bot_common/frame_watchdog.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace follow_bot_common {

FrameWatchdog::FrameWatchdog(double min_timeout_s, double expected_period_s)
    : min_timeout_s_(min_timeout_s), expected_period_s_(expected_period_s) {
  if (!std::isfinite(min_timeout_s) || min_timeout_s <= 0.0) {
    throw std::invalid_argument("FrameWatchdog: timeout must be finite and > 0, got " +
                                std::to_string(min_timeout_s));
  }
  if (!std::isfinite(expected_period_s) || expected_period_s < 0.0) {
    throw std::invalid_argument(
        "FrameWatchdog: expected frame period must be finite and >= 0, got " +
        std::to_string(expected_period_s));
  }
}

void FrameWatchdog::frameArrived(double t) {
  if (!std::isfinite(t)) return;
  if (has_frame_ && t > last_arrival_) {
    intervals_.push_back(t - last_arrival_);
    if (static_cast<int>(intervals_.size()) > kWindow) intervals_.pop_front();
    std::vector<double> sorted(intervals_.begin(), intervals_.end());
    const auto middle = sorted.begin() + static_cast<long>(sorted.size() / 2);
    std::nth_element(sorted.begin(), middle, sorted.end());
    interval_ = *middle;
  }
  last_arrival_ = t;
  aliveAt(t);
}

void FrameWatchdog::aliveAt(double t) {
  if (!std::isfinite(t)) return;
  if (!has_frame_) last_arrival_ = t;
  has_frame_ = true;
  last_frame_ = t;
  stop_sent_ = false;
}

double FrameWatchdog::timeout() const {
  const double period = intervals_.empty() ? expected_period_s_ : interval_;
  return std::max(min_timeout_s_, kPeriods * period);
}

bool FrameWatchdog::expired(double now) const {
  if (!has_frame_ || !std::isfinite(now)) return true;
  const double age = now - last_frame_;
  return age < 0.0 || age > timeout();
}

bool FrameWatchdog::shouldSendStop(double now) {
  if (!has_frame_ || stop_sent_ || !expired(now)) return false;
  stop_sent_ = true;
  return true;
}

void FrameWatchdog::reset() {
  has_frame_ = false;
  last_frame_ = 0.0;
  last_arrival_ = 0.0;
  intervals_.clear();
  interval_ = 0.0;
  stop_sent_ = false;
}

}  // namespace follow_bot_common
