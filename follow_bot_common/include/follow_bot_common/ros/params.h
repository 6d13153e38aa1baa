// Reading private parameters with their types and ranges checked: a value of the wrong type, a
// non-finite number or one out of range is a start-up error naming the ~param, never a silent
// default; a ~param the node never reads (a misspelt name) is named too (unknownParams). Shared
// by every nodelet of the project.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <ros/node_handle.h>
#include <ros/param.h>
#include <xmlrpcpp/XmlRpcValue.h>
#include <boost/any.hpp>

#include "follow_bot_common/ground_projection.h"
#include "follow_bot_common/nearest_name.h"

namespace follow_bot_common {

namespace detail {
// The ~params read so far, per private namespace (the nodelets of a manager share the process).
struct ParamsRead {
  std::mutex mutex;
  std::map<std::string, std::set<std::string>> names;
};
inline ParamsRead& paramsRead() {
  static ParamsRead read;
  return read;
}
}  // namespace detail

// Records that the node reads ~name, so unknownParams() knows it. param() records every read; a
// library that reads a ~param itself (diagnostic_updater, image_transport) is named with this.
inline void noteParamRead(const ros::NodeHandle& pnh, const std::string& name) {
  detail::ParamsRead& read = detail::paramsRead();
  std::lock_guard<std::mutex> lock(read.mutex);
  read.names[pnh.getNamespace()].insert(name);
}

// A ~param set that the node does not read, and the name it reads that is one typo away.
struct UnknownParam {
  std::string name;                    // without the ~
  std::optional<std::string> nearest;  // nearestName() among the names it reads
  // "~name is not a parameter of this node[; did you mean ~nearest?]"
  std::string describe() const {
    return "~" + name + " is not a parameter of this node" +
           (nearest ? "; did you mean ~" + *nearest + "?" : "");
  }
};

// The ~params set under `pnh` that the node has not read (noteParamRead): names it does not
// have, which would otherwise be silently ignored. Sub-namespaces are not judged: they hold the
// settings of the plugins on the node's topics (~debug_image/compressed/...).
inline std::vector<UnknownParam> unknownParams(const ros::NodeHandle& pnh) {
  XmlRpc::XmlRpcValue set;
  if (!ros::param::get(pnh.getNamespace(), set) ||
      set.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    return {};
  }
  std::vector<std::string> known;
  {
    detail::ParamsRead& read = detail::paramsRead();
    std::lock_guard<std::mutex> lock(read.mutex);
    const std::set<std::string>& names = read.names[pnh.getNamespace()];
    known.assign(names.begin(), names.end());
  }
  std::vector<UnknownParam> unknown;
  for (const auto& [name, value] : set) {
    if (value.getType() != XmlRpc::XmlRpcValue::TypeStruct &&
        !std::binary_search(known.begin(), known.end(), name)) {
      unknown.push_back({name, nearestName(name, known)});
    }
  }
  return unknown;
}

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

// How to read a T that only the XmlRpc type `kType` holds.
template <typename T, XmlRpc::XmlRpcValue::Type kType>
struct ExactParamType {
  static bool read(XmlRpc::XmlRpcValue& value, T& out) {
    if (value.getType() != kType) return false;
    out = static_cast<T&>(value);
    return true;
  }
};

template <>
struct ParamType<bool> : ExactParamType<bool, XmlRpc::XmlRpcValue::TypeBoolean> {
  static constexpr const char* kName = "a bool (true or false)";
};

template <>
struct ParamType<int> : ExactParamType<int, XmlRpc::XmlRpcValue::TypeInt> {
  static constexpr const char* kName = "an integer";
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
struct ParamType<std::string> : ExactParamType<std::string, XmlRpc::XmlRpcValue::TypeString> {
  static constexpr const char* kName = "a string";
};

// `name` from `pnh`, or `fallback` when unset; recorded as read (noteParamRead). Throws
// std::invalid_argument
// "~name must be <type>[ <requirement>], got <value>" when the value has another type.
template <typename T>
T param(const ros::NodeHandle& pnh, const std::string& name, T fallback,
        const std::string& requirement = "") {
  noteParamRead(pnh, name);
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

// A dynamic_reconfigure config whose server leaves the values asked for unclamped
// (dynamic_reconfigure::Server<Unclamped<ConfigT>> calls this __clamp__), so that the callback
// can say which ones it clamps (clampToRanges) instead of the server clamping them without a word.
template <typename ConfigT>
struct Unclamped : ConfigT {
  Unclamped() = default;
  Unclamped(const ConfigT& config) : ConfigT(config) {}  // NOLINT: the server converts the .cfg's
  void __clamp__() {}
};

// Clamps `config` to the ranges of its .cfg, as dynamic_reconfigure would; returns what that
// changed, one "~name: asked <value>, applied <value> (range)" per value.
template <typename ConfigT>
std::vector<std::string> clampToRanges(Unclamped<ConfigT>& config) {
  ConfigT clamped = config;
  clamped.__clamp__();
  std::vector<std::string> changes;
  const auto report = [&](const std::string& name, auto asked, auto applied, auto lo, auto hi) {
    if (asked == applied) return;
    std::ostringstream change;
    change << "~" << name << ": asked " << asked << ", applied " << applied << " (must be "
           << rangeText(lo, hi) << ")";
    changes.push_back(change.str());
  };
  for (const auto& description : ConfigT::__getParamDescriptions__()) {
    boost::any asked, applied, lo, hi;
    description->getValue(config, asked);
    description->getValue(clamped, applied);
    description->getValue(ConfigT::__getMin__(), lo);
    description->getValue(ConfigT::__getMax__(), hi);
    if (description->type == "int") {
      report(description->name, boost::any_cast<int>(asked), boost::any_cast<int>(applied),
             boost::any_cast<int>(lo), boost::any_cast<int>(hi));
    } else if (description->type == "double") {
      report(description->name, boost::any_cast<double>(asked), boost::any_cast<double>(applied),
             boost::any_cast<double>(lo), boost::any_cast<double>(hi));
    }
  }
  static_cast<ConfigT&>(config) = clamped;
  return changes;
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
inline CameraGeometry readCameraMounting(const ros::NodeHandle& pnh,
                                         const CameraGeometry& defaults = {}) {
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

}  // namespace follow_bot_common
