// The camera's health as /diagnostics reports it: whether frames arrive, at which rate, and
// what their absence did to the robot.
#pragma once

#include "follow_bot_common/status_report.h"

namespace follow_bot_common {

struct CameraHealth {
  bool frames_seen = false;     // a frame arrived since start-up
  bool frames_flowing = false;  // the frame watchdog has not expired
  bool stopped_by_watchdog =
      false;                   // frames stopped while the robot moved: the watchdog stopped it
  double interval = 0.0;       // s, the measured frame interval; 0 unknown
  double expected_rate = 0.0;  // Hz; 0 unknown
  double timeout = 0.0;        // s, the frame watchdog's timeout in force
};

// The relative deviation of the measured rate from the expected one that is still OK.
constexpr double kFrameRateTolerance = 0.2;

// ERROR only when the missing frames stopped the robot. No frames while nothing was commanded
// (idle, disabled, before the first frame): WARN, saying so. Frames flowing: OK, or WARN when an
// expected rate is given and the measured one is more than kFrameRateTolerance off it; an
// unknown expected rate accepts any.
StatusReport frameRateStatus(const CameraHealth& health);

}  // namespace follow_bot_common
