#include "follow_bot/steering_law.h"

#include <sstream>
#include <stdexcept>

#include "follow_bot/common.h"
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

std::string validate(const SteeringConfig& c) {
  for (const std::string& error : {
           checkFields(c),
           requireAtMostMaxLinear("min_linear", c.min_linear, c.max_linear),
           checkFields(c.pd),
           checkFields(c.search),
           requireAtMostMaxLinear("lost_linear", c.search.lost_linear, c.max_linear),
           checkFields(c.path),
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
