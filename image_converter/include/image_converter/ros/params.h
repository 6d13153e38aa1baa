// Reading private parameters, optionally with validation: a bad value is a startup error
// naming it. Shared by both packages' nodelets (follow_bot's ros/params.h adds its own).
#pragma once

#include <cmath>
#include <stdexcept>
#include <string>

#include <ros/node_handle.h>

namespace image_converter {

// `name` from `pnh`, or `fallback` when unset.
template <typename T>
T param(const ros::NodeHandle& pnh, const std::string& name, T fallback) {
  T value = fallback;
  pnh.param(name, value, fallback);
  return value;
}

// Reads `name` from `pnh` (or `fallback`) and throws std::invalid_argument
// "~name must be <requirement>, got <value>" unless `ok(value)`.
template <typename T, typename Check>
T checkedParam(const ros::NodeHandle& pnh, const std::string& name, T fallback, Check ok,
               const std::string& requirement) {
  const T value = param(pnh, name, fallback);
  if (!ok(value)) {
    throw std::invalid_argument("~" + name + " must be " + requirement + ", got " +
                                std::to_string(value));
  }
  return value;
}

inline double positiveParam(const ros::NodeHandle& pnh, const std::string& name, double fallback) {
  return checkedParam(
      pnh, name, fallback, [](double v) { return std::isfinite(v) && v > 0.0; }, "> 0");
}

}  // namespace image_converter
