// A core's health as /diagnostics shows it, ROS-free: BehaviourNodelet::addDiagnostics publishes
// it as a diagnostic_updater status.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace follow_bot_common {

struct StatusReport {
  // The values of diagnostic_msgs/DiagnosticStatus's OK, WARN and ERROR.
  enum class Level : unsigned char { kOk = 0, kWarn = 1, kError = 2 };
  Level level = Level::kOk;
  std::string message;
  std::vector<std::pair<std::string, std::string>> values;  // key, value; in this order
};

}  // namespace follow_bot_common
