// The validate() checks live in image_converter's core next to the VelocityLimiter that uses
// them; follow_bot code keeps using them under these names.
#pragma once

#include "image_converter/config_checks.h"

namespace follow_bot {

using image_converter::requireAtLeast;
using image_converter::requireFinite;
using image_converter::requireInRange;
using image_converter::requirePositive;

}  // namespace follow_bot
