// Turning a behaviour's .cfg values into its cores' configurations: the checks every mapping
// makes, in the one message style of the ~params ("~name must be <rule>, got <value>"). The
// .cfg's ranges are checked before (readConfig, or the dynamic_reconfigure server's clamping).
#pragma once

#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <string>

namespace follow_bot {

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

}  // namespace follow_bot
