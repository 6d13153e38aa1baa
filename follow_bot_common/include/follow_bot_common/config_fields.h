// A core Config struct's plain fields, listed once next to their members: each with its name (in
// validate()'s messages and in Python), its member, the rule validate() holds it to, and the .cfg
// parameter that sets it, if any. validate() (checkFields), the nodelets' .cfg mapping
// (config_mapping.h, assignFromConfig) and the Python bindings (pybind_support.h, bindFields)
// expand the list, so a new field is its .cfg line, its member and its line in the list.
//
// A struct lists its fields in `static constexpr auto fields()`, e.g.
//   static constexpr auto fields() {
//     return std::make_tuple(cfgField("kp", &PdConfig::kp, atLeast(0.0)),
//                            field("max_derivative_dt", &PdConfig::max_derivative_dt, positive()));
//   }
// Fields that are choices (an enum, a colour's name), nested structs or linked to other fields
// keep their own code.
#pragma once

#include <cstddef>
#include <sstream>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "follow_bot_common/config_checks.h"

namespace follow_bot_common {

// What validate() requires of a numeric field, in config_checks.h's messages.
struct FieldRule {
  enum class Kind { kNone, kFinite, kPositive, kAtLeast, kInRange, kAboveAtMost };
  Kind kind = Kind::kNone;
  double min = 0.0;
  double max = 0.0;
  const char* why = nullptr;  // said after the message, in brackets

  // The same rule, its message followed by " (why)".
  constexpr FieldRule because(const char* reason) const {
    FieldRule rule = *this;
    rule.why = reason;
    return rule;
  }

  // The rule as the messages say it ("> 0", ">= 0", "in [0, 1]", "in (0, 1]"); "" for none and
  // for finite, which a ~param's type already says.
  std::string text() const {
    std::ostringstream out;
    switch (kind) {
      case Kind::kNone:
      case Kind::kFinite:
        break;
      case Kind::kPositive:
        out << "> 0";
        break;
      case Kind::kAtLeast:
        out << ">= " << min;
        break;
      case Kind::kInRange:
        out << "in [" << min << ", " << max << "]";
        break;
      case Kind::kAboveAtMost:
        out << "in (" << min << ", " << max << "]";
        break;
    }
    return out.str();
  }

  // "" when `value` meets the rule, otherwise "<name> must be <rule>, got <value>[ (why)]".
  std::string check(const char* name, double value) const {
    std::string error = bare(name, value);
    if (!error.empty() && why != nullptr) error += std::string(" (") + why + ")";
    return error;
  }

 private:
  std::string bare(const char* name, double value) const {
    switch (kind) {
      case Kind::kNone:
        return "";
      case Kind::kFinite:
        return requireFinite(name, value);
      case Kind::kPositive:
        return requirePositive(name, value);
      case Kind::kAtLeast:
        return requireAtLeast(name, value, min);
      case Kind::kInRange:
        return requireInRange(name, value, min, max);
      case Kind::kAboveAtMost:
        return requireAboveAtMost(name, value, min, max);
    }
    return "";
  }
};

constexpr FieldRule finite() { return {FieldRule::Kind::kFinite}; }
constexpr FieldRule positive() { return {FieldRule::Kind::kPositive}; }
constexpr FieldRule atLeast(double min) { return {FieldRule::Kind::kAtLeast, min}; }
constexpr FieldRule inRange(double min, double max) {
  return {FieldRule::Kind::kInRange, min, max};
}
constexpr FieldRule aboveAtMost(double min, double max) {
  return {FieldRule::Kind::kAboveAtMost, min, max};
}

template <typename Struct, typename T>
struct Field {
  const char* name;  // the member's name
  T Struct::*member;
  FieldRule rule;
  const char* cfg_param;  // the .cfg parameter that sets it; nullptr: none (a core-only field)
  double cfg_scale;       // the field is the parameter times this (a unit: degrees to radians)
};

// A field no .cfg parameter sets.
template <typename Struct, typename T>
constexpr Field<Struct, T> field(const char* name, T Struct::*member, FieldRule rule = {}) {
  return {name, member, rule, nullptr, 1.0};
}

// A field the .cfg parameter `cfg_param` (by default, the one of the same name) sets, times
// `cfg_scale` (floating-point fields only).
template <typename Struct, typename T>
constexpr Field<Struct, T> cfgField(const char* name, T Struct::*member, FieldRule rule = {},
                                    const char* cfg_param = nullptr, double cfg_scale = 1.0) {
  return {name, member, rule, cfg_param != nullptr ? cfg_param : name, cfg_scale};
}

// Calls `visit(field)` for each of Struct::fields().
template <typename Struct, typename Visit>
void forEachField(Visit&& visit) {
  std::apply([&](const auto&... each) { (visit(each), ...); }, Struct::fields());
}

// The first of `config`'s listed fields that breaks its rule, as its message; "" when none.
template <typename Struct>
std::string checkFields(const Struct& config) {
  std::string error;
  forEachField<Struct>([&](const auto& field) {
    using T = std::decay_t<decltype(config.*field.member)>;
    if constexpr (std::is_arithmetic_v<T> && !std::is_same_v<T, bool>) {
      if (error.empty())
        error = field.rule.check(field.name, static_cast<double>(config.*field.member));
    }
  });
  return error;
}

}  // namespace follow_bot_common
