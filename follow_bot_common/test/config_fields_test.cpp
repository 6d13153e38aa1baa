#include "follow_bot_common/config_fields.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>
#include <vector>

namespace follow_bot_common {
namespace {

struct Example {
  double gain = 1.0;
  int count = 3;
  double fraction = 0.5;
  double offset = 0.0;
  std::string name = "x";
  bool enabled = true;

  static constexpr auto fields() {
    using C = Example;
    return std::make_tuple(cfgField("gain", &C::gain, positive()),
                           field("count", &C::count, atLeast(1)),
                           cfgField("fraction", &C::fraction, inRange(0.0, 1.0), "share", 0.01),
                           field("offset", &C::offset, finite()), cfgField("name", &C::name),
                           field("enabled", &C::enabled));
  }
};

TEST(ConfigFields, ListsEachFieldInOrderWithItsParameter) {
  std::vector<std::string> names;
  std::vector<std::string> params;
  forEachField<Example>([&](const auto& field) {
    names.emplace_back(field.name);
    params.emplace_back(field.cfg_param != nullptr ? field.cfg_param : "-");
  });
  EXPECT_EQ(names,
            (std::vector<std::string>{"gain", "count", "fraction", "offset", "name", "enabled"}));
  // A field without a parameter name takes its own; a core-only field has none.
  EXPECT_EQ(params, (std::vector<std::string>{"gain", "-", "share", "-", "name", "-"}));
  EXPECT_DOUBLE_EQ(std::get<2>(Example::fields()).cfg_scale, 0.01);
  EXPECT_DOUBLE_EQ(std::get<0>(Example::fields()).cfg_scale, 1.0);
}

TEST(ConfigFields, ChecksEachRuleInTheMessagesOfConfigChecks) {
  EXPECT_EQ(checkFields(Example()), "");
  const auto error_for = [](auto change) {
    Example example;
    change(example);
    return checkFields(example);
  };
  EXPECT_EQ(error_for([](Example& e) { e.gain = 0.0; }), "gain must be > 0, got 0");
  EXPECT_EQ(error_for([](Example& e) { e.count = 0; }), "count must be >= 1, got 0");
  EXPECT_EQ(error_for([](Example& e) { e.fraction = 1.5; }), "fraction must be in [0, 1], got 1.5");
  EXPECT_EQ(error_for([](Example& e) { e.offset = -INFINITY; }), "offset must be finite, got -inf");
  // NaN breaks every rule, an order comparison included.
  EXPECT_EQ(error_for([](Example& e) { e.fraction = std::nan(""); }),
            "fraction must be in [0, 1], got nan");
  // The first broken rule in the list's order.
  EXPECT_EQ(error_for([](Example& e) {
              e.offset = NAN;
              e.count = -2;
            }),
            "count must be >= 1, got -2");
}

TEST(ConfigFields, AHalfOpenRangeAndAReason) {
  const FieldRule ratio = aboveAtMost(0.0, 1.0);
  EXPECT_EQ(ratio.check("ratio", 1.0), "");
  EXPECT_EQ(ratio.check("ratio", 0.0), "ratio must be in (0, 1], got 0");
  EXPECT_EQ(ratio.check("ratio", INFINITY), "ratio must be in (0, 1], got inf");
  const FieldRule points = atLeast(4).because("a homography needs 4 points");
  EXPECT_EQ(points.check("min_inliers", 4), "");
  EXPECT_EQ(points.check("min_inliers", 3),
            "min_inliers must be >= 4, got 3 (a homography needs 4 points)");
}

TEST(ConfigFields, SaysEachRuleAsTheParamMessagesDo) {
  EXPECT_EQ(FieldRule().text(), "");
  EXPECT_EQ(finite().text(), "");  // a ~param's type says it: "a finite number"
  EXPECT_EQ(positive().text(), "> 0");
  EXPECT_EQ(atLeast(0.5).text(), ">= 0.5");
  EXPECT_EQ(inRange(0.0, 1.0).text(), "in [0, 1]");
  EXPECT_EQ(aboveAtMost(0.0, 2.5).text(), "in (0, 2.5]");
}

}  // namespace
}  // namespace follow_bot_common
