// The VelocityLimiter lives in image_converter's core, so image_converter's own nodes (the
// panorama turner) share it; follow_bot code keeps using it under these names.
#pragma once

#include "image_converter/velocity_limiter.h"

namespace follow_bot {

using image_converter::Twist2D;
using image_converter::validate;
using image_converter::VelocityLimiter;
using image_converter::VelocityLimiterConfig;

}  // namespace follow_bot
