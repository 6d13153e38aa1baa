#include "follow_bot_common/frame_watchdog.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace follow_bot {

FrameWatchdog::FrameWatchdog(double timeout_s) : timeout_s_(timeout_s) {
  if (!std::isfinite(timeout_s) || timeout_s <= 0.0) {
    throw std::invalid_argument("FrameWatchdog: timeout must be finite and > 0, got " +
                                std::to_string(timeout_s));
  }
}

void FrameWatchdog::frameArrived(double t) {
  if (!std::isfinite(t)) return;
  has_frame_ = true;
  last_frame_ = t;
  stop_sent_ = false;
}

bool FrameWatchdog::expired(double now) const {
  if (!has_frame_ || !std::isfinite(now)) return true;
  const double age = now - last_frame_;
  return age < 0.0 || age > timeout_s_;
}

bool FrameWatchdog::shouldSendStop(double now) {
  if (!has_frame_ || stop_sent_ || !expired(now)) return false;
  stop_sent_ = true;
  return true;
}

void FrameWatchdog::reset() {
  has_frame_ = false;
  last_frame_ = 0.0;
  stop_sent_ = false;
}

}  // namespace follow_bot
