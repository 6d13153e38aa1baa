#include "follow_bot_common/frame_rate_status.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace follow_bot_common {

namespace {
std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), pattern, value);
  return text;
}
}  // namespace

StatusReport frameRateStatus(const CameraHealth& health) {
  using Level = StatusReport::Level;
  const double rate = health.interval > 0.0 ? 1.0 / health.interval : 0.0;
  const std::string rate_text = rate > 0.0 ? format("%.1f", rate) : "unknown";
  StatusReport report;
  if (!health.frames_seen) {
    report = {Level::kWarn, "no frames yet, idle", {}};
  } else if (!health.frames_flowing) {
    report = health.stopped_by_watchdog
                 ? StatusReport{Level::kError, "no frames: the watchdog stopped the robot", {}}
                 : StatusReport{Level::kWarn, "no frames, idle: nothing to stop", {}};
  } else if (rate > 0.0 && health.expected_rate > 0.0 &&
             std::abs(rate - health.expected_rate) > kFrameRateTolerance * health.expected_rate) {
    report = {Level::kWarn,
              rate_text + " Hz, expected " + format("%.1f", health.expected_rate) + " Hz",
              {}};
  } else {
    report = {Level::kOk, rate > 0.0 ? rate_text + " Hz" : "frames arriving", {}};
  }
  report.values = {
      {"measured rate (Hz)", rate_text},
      {"expected rate (Hz)",
       health.expected_rate > 0.0 ? format("%.1f", health.expected_rate) : "unknown"},
      {"watchdog timeout (s)", format("%.3f", health.timeout)},
  };
  return report;
}

}  // namespace follow_bot_common
