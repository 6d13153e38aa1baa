// An enum's names in one table, read both ways: a value's name (toString, the ~status topics,
// the Python enums) and the value a ~param's name stands for (parse). Names are lower case with
// underscores, as on every ~status topic.
//
//   inline constexpr EnumName<SteeringMode> kSteeringModeNames[] = {
//       {SteeringMode::kLecture, "lecture"}, {SteeringMode::kPD, "pd"}, ...};
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>

namespace follow_bot_common {

template <typename Enum>
struct EnumName {
  Enum value;
  const char* name;
};

// `value`'s name in `names`; "unknown" for a value the table lacks (a cast integer).
template <typename Enum, std::size_t N>
constexpr const char* nameIn(const EnumName<Enum> (&names)[N], Enum value) {
  for (const EnumName<Enum>& entry : names) {
    if (entry.value == value) return entry.name;
  }
  return "unknown";
}

// The value `name` stands for in `names`; nothing for another name.
template <typename Enum, std::size_t N>
constexpr std::optional<Enum> valueIn(const EnumName<Enum> (&names)[N], std::string_view name) {
  for (const EnumName<Enum>& entry : names) {
    if (name == entry.name) return entry.value;
  }
  return std::nullopt;
}

}  // namespace follow_bot_common
