// Reading private parameters with validation: a bad value is a startup error naming it.
#pragma once

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <ros/node_handle.h>
#include <boost/any.hpp>

#include "follow_bot/ground_projection.h"
#include "image_converter/ros/params.h"

namespace follow_bot {

using image_converter::checkedParam;
using image_converter::param;
using image_converter::positiveParam;

// The camera's mounting over `defaults`: ~camera_height (m, > 0), ~camera_pitch_deg (deg, down
// positive, within (-89, 89)), ~camera_x_offset (m, forward of base_link, finite). Intrinsics
// arrive later with camera_info. Throws std::invalid_argument naming the first bad value.
inline CameraGeometry readCameraMounting(const ros::NodeHandle& pnh, CameraGeometry defaults = {}) {
  CameraGeometry camera = defaults;
  camera.height_m = positiveParam(pnh, "camera_height", defaults.height_m);
  const double pitch_deg = checkedParam(
      pnh, "camera_pitch_deg", defaults.pitch_rad * 180.0 / M_PI,
      [](double v) { return std::isfinite(v) && std::abs(v) < 89.0; }, "within (-89, 89)");
  camera.pitch_rad = pitch_deg * M_PI / 180.0;
  camera.x_offset_m = checkedParam(
      pnh, "camera_x_offset", defaults.x_offset_m, [](double v) { return std::isfinite(v); },
      "finite");
  return camera;
}

// "in [lo, hi]", "<= hi", ">= lo" or "" (unbounded), as the .cfg declares a parameter's range.
template <typename T>
std::string rangeText(T lo, T hi) {
  const bool has_lo = lo > std::numeric_limits<T>::lowest();
  const bool has_hi = hi < std::numeric_limits<T>::max();
  std::ostringstream out;
  if (has_lo && has_hi) {
    out << "in [" << lo << ", " << hi << "]";
  } else if (has_lo) {
    out << ">= " << lo;
  } else if (has_hi) {
    out << "<= " << hi;
  }
  return out.str();
}

// One ~param of a .cfg, checked for the type and range the .cfg declares.
template <typename T, typename ConfigT, typename Description>
void checkConfigParam(const ros::NodeHandle& pnh, const Description& description) {
  boost::any fallback, lo, hi;
  description.getValue(ConfigT::__getDefault__(), fallback);
  description.getValue(ConfigT::__getMin__(), lo);
  description.getValue(ConfigT::__getMax__(), hi);
  if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
    const T min = boost::any_cast<T>(lo), max = boost::any_cast<T>(hi);
    checkedParam(
        pnh, description.name, boost::any_cast<T>(fallback),
        [&](T value) { return min <= value && value <= max; }, rangeText(min, max));
  } else {
    param(pnh, description.name, boost::any_cast<T>(fallback));
  }
}

// A dynamic_reconfigure config (generated `ConfigT`) from the ~params, each checked against the
// type and range its .cfg declares: __fromServer__ alone keeps the default for a value of the
// wrong type, and nothing clamps start-up values. Throws std::invalid_argument naming the
// ~param, its type and range.
template <typename ConfigT>
ConfigT readConfig(const ros::NodeHandle& pnh) {
  for (const auto& description : ConfigT::__getParamDescriptions__()) {
    if (description->type == "int") {
      checkConfigParam<int, ConfigT>(pnh, *description);
    } else if (description->type == "double") {
      checkConfigParam<double, ConfigT>(pnh, *description);
    } else if (description->type == "bool") {
      checkConfigParam<bool, ConfigT>(pnh, *description);
    } else {
      checkConfigParam<std::string, ConfigT>(pnh, *description);
    }
  }
  ConfigT config = ConfigT::__getDefault__();
  config.__fromServer__(pnh);
  return config;
}

// A dynamic_reconfigure callback's core: `apply(config)`, and on success `config` is the one in
// force. When `apply` rejects it (std::invalid_argument), `config` is reset to `in_force`, so the
// server reports back, and later updates build on, the settings actually in force. Returns the
// rejection's reason, "" when applied.
template <typename ConfigT, typename Apply>
std::string applyOrKeep(ConfigT& config, ConfigT& in_force, Apply apply) {
  try {
    apply(config);
    in_force = config;
    return "";
  } catch (const std::invalid_argument& error) {
    config = in_force;
    return error.what();
  }
}

}  // namespace follow_bot
