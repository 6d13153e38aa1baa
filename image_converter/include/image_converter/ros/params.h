// Reading private parameters with their types and ranges checked: a value of the wrong type, a
// non-finite number or one out of range is a start-up error naming the ~param, never a silent
// default. Shared by both packages' nodelets (follow_bot's ros/params.h adds its own).
#pragma once

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

namespace image_converter {

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

}  // namespace image_converter
