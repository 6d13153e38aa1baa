#include "follow_bot/steering_law.h"

#include <sstream>
#include <stdexcept>

#include "follow_bot/line_controller.h"
#include "follow_bot/line_path.h"
#include "follow_bot_common/config_checks.h"

namespace follow_bot {
namespace {

std::string requireAtMostMaxLinear(const char* name, double value, double max_linear) {
  if (value <= max_linear) return "";
  std::ostringstream message;
  message << name << " (" << value << ") must be <= max_linear (" << max_linear << ")";
  return message.str();
}

}  // namespace

std::optional<SteeringMode> parseSteeringMode(const std::string& name) {
  for (SteeringMode mode : {SteeringMode::kLecture, SteeringMode::kPD, SteeringMode::kPath}) {
    if (name == toString(mode)) return mode;
  }
  return std::nullopt;
}

const char* toString(SteeringMode mode) {
  switch (mode) {
    case SteeringMode::kLecture:
      return "lecture";
    case SteeringMode::kPD:
      return "pd";
    case SteeringMode::kPath:
      return "path";
  }
  return "unknown";
}

const char* toString(LineState state) {
  switch (state) {
    case LineState::kFollowing:
      return "following";
    case LineState::kLost:
      return "lost";
    case LineState::kSearching:
      return "searching";
    case LineState::kGaveUp:
      return "gave_up";
  }
  return "unknown";
}

std::string validate(const SteeringConfig& c) {
  const PdConfig& pd = c.pd;
  const LineSearchConfig& search = c.search;
  const PathConfig& path = c.path;
  for (const std::string& error : {
           requirePositive("max_linear", c.max_linear),
           requireAtLeast("min_linear", c.min_linear, 0.0),
           requireAtMostMaxLinear("min_linear", c.min_linear, c.max_linear),
           requirePositive("max_angular", c.max_angular),
           requireInRange("min_confidence", c.min_confidence, 0.0, 1.0),
           requireAtLeast("kp", pd.kp, 0.0),
           requireAtLeast("kd", pd.kd, 0.0),
           requirePositive("max_derivative_dt", pd.max_derivative_dt),
           requireInRange("look_ahead_weight", pd.look_ahead_weight, 0.0, 1.0),
           requireAtLeast("taper", pd.taper, 0.0),
           requireAtLeast("curvature_taper", pd.curvature_taper, 0.0),
           requireAtLeast("lost_grace", search.lost_grace, 0.0),
           requireAtLeast("lost_linear", search.lost_linear, 0.0),
           requireAtMostMaxLinear("lost_linear", search.lost_linear, c.max_linear),
           requireAtLeast("lost_angular", search.lost_angular, 0.0),
           requireAtLeast("search_rate", search.search_rate, 0.0),
           requireAtLeast("search_timeout", search.search_timeout, 0.0),
           requireAtLeast("heading_gain", path.heading_gain, 0.0),
           requireAtLeast("lateral_gain", path.lateral_gain, 0.0),
           requirePositive("fit_length", path.fit_length),
           requireAtLeast("max_extrapolation", path.max_extrapolation, 0.0),
           requirePositive("start_lookahead", path.start_lookahead),
           requireAtLeast("keep_behind", path.keep_behind, 0.0),
           requirePositive("max_point_age", path.max_point_age),
           requireAtLeast("max_points", path.max_points, 3),
           requireAtLeast("min_point_spacing", path.min_point_spacing, 0.0),
           requirePositive("bridge_gap", path.bridge_gap),
           requirePositive("max_frame_gap", path.max_frame_gap),
           requireInRange("command_latency", path.command_latency, 0.0, 1.0),
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

std::unique_ptr<SteeringLaw> makeSteeringLaw(const SteeringConfig& config,
                                             const std::optional<CameraGeometry>& camera) {
  // Every mode validates every section, so a configuration is accepted or rejected alike
  // whichever law it starts with.
  const std::string error = validate(config);
  if (!error.empty()) throw std::invalid_argument(error);
  switch (config.mode) {
    case SteeringMode::kLecture:
      return std::make_unique<LectureLaw>();
    case SteeringMode::kPD:
      return std::make_unique<PdLaw>(config);
    case SteeringMode::kPath:
      if (!camera) return std::make_unique<PdLaw>(config);
      return std::make_unique<PathLaw>(config, *camera);
  }
  throw std::invalid_argument("unknown steering mode");
}

}  // namespace follow_bot
