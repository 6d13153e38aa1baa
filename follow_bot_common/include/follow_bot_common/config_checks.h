// Checks shared by the core's validate() functions: each returns "" when the value is fine,
// otherwise "<name> must be <rule>, got <value>". NaN and infinities always fail.
#pragma once

#include <cmath>
#include <sstream>
#include <string>

namespace follow_bot_common {

inline std::string requireFinite(const char* name, double value) {
  if (std::isfinite(value)) return "";
  std::ostringstream message;
  message << name << " must be finite, got " << value;
  return message.str();
}

inline std::string requirePositive(const char* name, double value) {
  if (std::isfinite(value) && value > 0.0) return "";
  std::ostringstream message;
  message << name << " must be > 0, got " << value;
  return message.str();
}

inline std::string requireAtLeast(const char* name, double value, double min) {
  if (std::isfinite(value) && value >= min) return "";
  std::ostringstream message;
  message << name << " must be >= " << min << ", got " << value;
  return message.str();
}

inline std::string requireInRange(const char* name, double value, double min, double max) {
  if (std::isfinite(value) && value >= min && value <= max) return "";
  std::ostringstream message;
  message << name << " must be in [" << min << ", " << max << "], got " << value;
  return message.str();
}

// In (min, max]: above min, at most max.
inline std::string requireAboveAtMost(const char* name, double value, double min, double max) {
  if (std::isfinite(value) && value > min && value <= max) return "";
  std::ostringstream message;
  message << name << " must be in (" << min << ", " << max << "], got " << value;
  return message.str();
}

}  // namespace follow_bot_common
