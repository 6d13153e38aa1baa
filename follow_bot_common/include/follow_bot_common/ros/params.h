// Reading private parameters with their types and ranges checked: a value of the wrong type, a
// non-finite number or one out of range is a start-up error naming the ~param, never a silent
// default. Shared by every nodelet of the project.
#pragma once

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <boost/any.hpp>

#include "follow_bot_common/ground_projection.h"

namespace follow_bot {

// "the string 'abc'", "the number 2.5", ...: what the user gave, for error messages.
inline std::string describeValue(XmlRpc::XmlRpcValue& value) {
  std::ostringstream out;
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeString:
      return "the string '" + static_cast<std::string&>(value) + "'";
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return std::string("the bool ") + (static_cast<bool&>(value) ? "true" : "false");
    case XmlRpc::XmlRpcValue::TypeInt:
      return "the integer " + std::to_string(static_cast<int&>(value));
    case XmlRpc::XmlRpcValue::TypeDouble:
      out << "the number " << static_cast<double&>(value);
      return out.str();
    default:
      value.write(out);
      return "a value of another type (" + out.str() + ")";
  }
}

// The C++ types a ~param can have: how to read one from the parameter server, and its name.
template <typename T>
struct ParamType;

template <>
struct ParamType<bool> {
  static constexpr const char* kName = "a bool (true or false)";
  static bool read(XmlRpc::XmlRpcValue& value, bool& out) {
    if (value.getType() != XmlRpc::XmlRpcValue::TypeBoolean) return false;
    out = value;
    return true;
  }
};

template <>
struct ParamType<int> {
  static constexpr const char* kName = "an integer";
  static bool read(XmlRpc::XmlRpcValue& value, int& out) {
    if (value.getType() != XmlRpc::XmlRpcValue::TypeInt) return false;
    out = value;
    return true;
  }
};

// An integer is a number too; NaN and infinities are not (no parameter means "no limit").
template <>
struct ParamType<double> {
  static constexpr const char* kName = "a finite number";
  static bool read(XmlRpc::XmlRpcValue& value, double& out) {
    if (value.getType() == XmlRpc::XmlRpcValue::TypeInt) {
      out = static_cast<int&>(value);
      return true;
    }
    if (value.getType() != XmlRpc::XmlRpcValue::TypeDouble) return false;
    out = value;
    return std::isfinite(out);
  }
};

template <>
struct ParamType<std::string> {
  static constexpr const char* kName = "a string";
  static bool read(XmlRpc::XmlRpcValue& value, std::string& out) {
    if (value.getType() != XmlRpc::XmlRpcValue::TypeString) return false;
    out = static_cast<std::string&>(value);
    return true;
  }
};

// `name` from `pnh`, or `fallback` when unset. Throws std::invalid_argument
// "~name must be <type>[ <requirement>], got <value>" when the value has another type.
template <typename T>
T param(const ros::NodeHandle& pnh, const std::string& name, T fallback,
        const std::string& requirement = "") {
  XmlRpc::XmlRpcValue value;
  if (!pnh.getParam(name, value)) return fallback;
  T out = fallback;
  if (!ParamType<T>::read(value, out)) {
    throw std::invalid_argument("~" + name + " must be " + ParamType<T>::kName +
                                (requirement.empty() ? "" : " " + requirement) + ", got " +
                                describeValue(value));
  }
  return out;
}

// Reads `name` from `pnh` (or `fallback`) and throws std::invalid_argument
// "~name must be <requirement>, got <value>" unless it has type T and `ok(value)`.
template <typename T, typename Check>
T checkedParam(const ros::NodeHandle& pnh, const std::string& name, T fallback, Check ok,
               const std::string& requirement) {
  const T value = param(pnh, name, fallback, requirement);
  if (!ok(value)) {
    std::ostringstream got;
    got << value;
    throw std::invalid_argument("~" + name + " must be " + requirement + ", got " + got.str());
  }
  return value;
}

inline double positiveParam(const ros::NodeHandle& pnh, const std::string& name, double fallback) {
  return checkedParam(
      pnh, name, fallback, [](double v) { return v > 0.0; }, "> 0");
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

}  // namespace follow_bot
