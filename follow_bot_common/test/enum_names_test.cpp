#include "follow_bot_common/enum_names.h"

#include <gtest/gtest.h>

#include <string>

namespace follow_bot_common {
namespace {

enum class Light { kRed, kAmber, kGreen };
constexpr EnumName<Light> kLightNames[] = {
    {Light::kRed, "red"}, {Light::kAmber, "amber"}, {Light::kGreen, "green"}};

TEST(EnumNames, ReadsTheTableBothWays) {
  EXPECT_EQ(std::string(nameIn(kLightNames, Light::kAmber)), "amber");
  EXPECT_EQ(valueIn(kLightNames, "green"), Light::kGreen);
  // Names are matched exactly: another case or a prefix is another name.
  EXPECT_EQ(valueIn(kLightNames, "Green"), std::nullopt);
  EXPECT_EQ(valueIn(kLightNames, "gre"), std::nullopt);
  EXPECT_EQ(std::string(nameIn(kLightNames, static_cast<Light>(7))), "unknown");
  static_assert(*valueIn(kLightNames, "red") == Light::kRed, "usable at compile time");
}

}  // namespace
}  // namespace follow_bot_common
