// Turning a behaviour's .cfg values into its cores' configurations: the checks every mapping
// makes, in the one message style of the ~params ("~name must be <rule>, got <value>"). The
// .cfg's ranges are checked before (readConfig, or the dynamic_reconfigure server's clamping).
#pragma once

#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <boost/any.hpp>

#include "follow_bot_common/config_fields.h"
#include "follow_bot_common/ros/params.h"

namespace follow_bot_common {

// `parse(value)` (a std::optional), or std::invalid_argument "~name must be <choices>, got
// '<value>'" when it gives nothing.
template <typename Parse>
auto parseChoice(const std::string& name, const std::string& value, Parse parse,
                 const std::string& choices) {
  auto parsed = parse(value);
  if (!parsed) {
    throw std::invalid_argument("~" + name + " must be " + choices + ", got '" + value + "'");
  }
  return *parsed;
}

// Throws std::invalid_argument with the first non-empty message (the cores' validate()).
inline void requireValid(std::initializer_list<std::string> errors) {
  for (const std::string& error : errors) {
    if (!error.empty()) throw std::invalid_argument(error);
  }
}

// Throws std::invalid_argument "<rule>, got <a> and <b>" unless `ok`: a rule linking two ~params.
inline void requireLinked(bool ok, const std::string& rule, double a, double b) {
  if (ok) return;
  std::ostringstream error;
  error << rule << ", got " << a << " and " << b;
  throw std::invalid_argument(error.str());
}

// The value of the .cfg parameter `name` in `config` (a generated dynamic_reconfigure ConfigT), as
// a T: an int parameter sets an int or double field. std::logic_error when the .cfg lacks it or
// its type does not fit: a field list naming the wrong parameter, a bug.
template <typename T, typename ConfigT>
T configValue(const ConfigT& config, const std::string& name) {
  for (const auto& description : ConfigT::__getParamDescriptions__()) {
    if (description->name != name) continue;
    boost::any value;
    description->getValue(config, value);
    if constexpr (std::is_same_v<T, bool> || std::is_same_v<T, std::string>) {
      if (const T* exact = boost::any_cast<T>(&value)) return *exact;
    } else if constexpr (std::is_arithmetic_v<T>) {
      if (const T* exact = boost::any_cast<T>(&value)) return *exact;
      if (const int* whole = boost::any_cast<int>(&value)) return static_cast<T>(*whole);
    }
    throw std::logic_error("the .cfg parameter " + name + " (" + description->type +
                           ") cannot set a field of this type");
  }
  throw std::logic_error(name + " is not a parameter of the .cfg");
}

// Sets each of `core`'s listed fields (Struct::fields(), config_fields.h) that a .cfg parameter
// sets from `config`; the rest keep their values.
template <typename Struct, typename ConfigT>
void assignFromConfig(Struct& core, const ConfigT& config) {
  forEachField<Struct>([&](const auto& field) {
    using T = std::decay_t<decltype(core.*field.member)>;
    if (field.cfg_param == nullptr) return;
    core.*field.member = configValue<T>(config, field.cfg_param);
    if constexpr (std::is_floating_point_v<T>) core.*field.member *= field.cfg_scale;
  });
}

// Sets each of `core`'s listed fields that a .cfg parameter sets from that ~param, for a .cfg
// read once at start-up (no dynamic_reconfigure server): a param left unset keeps the field's
// value; one of another type or breaking the field's rule throws std::invalid_argument
// "~param must be <rule>, got <value>".
template <typename Struct>
void readFieldParams(const ros::NodeHandle& pnh, Struct& core) {
  forEachField<Struct>([&](const auto& field) {
    using T = std::decay_t<decltype(core.*field.member)>;
    if (field.cfg_param == nullptr) return;
    if (field.cfg_scale != 1.0) {
      throw std::logic_error(std::string(field.cfg_param) +
                             ": a start-up parameter is the field itself, unscaled");
    }
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      core.*field.member = checkedParam(
          pnh, field.cfg_param, core.*field.member,
          [&](T value) { return field.rule.check("", static_cast<double>(value)).empty(); },
          field.rule.text());
    } else {
      core.*field.member = param(pnh, field.cfg_param, core.*field.member);
    }
  });
}

}  // namespace follow_bot_common
