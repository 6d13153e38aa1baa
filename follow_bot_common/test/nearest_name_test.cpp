#include "follow_bot_common/nearest_name.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace follow_bot_common {
namespace {

TEST(EditDistance, CountsTheUsualTypos) {
  EXPECT_EQ(editDistance("", ""), 0u);
  EXPECT_EQ(editDistance("kp", "kp"), 0u);
  EXPECT_EQ(editDistance("", "kp"), 2u);
  EXPECT_EQ(editDistance("max_liner", "max_linear"), 1u);    // a letter left out
  EXPECT_EQ(editDistance("max_linnear", "max_linear"), 1u);  // one too many
  EXPECT_EQ(editDistance("max_lineer", "max_linear"), 1u);   // a wrong one
  EXPECT_EQ(editDistance("max_lienar", "max_linear"), 1u);   // two swapped
  EXPECT_EQ(editDistance("kitten", "sitting"), 3u);          // the textbook pair
  EXPECT_EQ(editDistance("ca", "abc"), 3u);  // OSA: a swapped pair is not edited again
}

TEST(EditDistance, IsSymmetric) {
  EXPECT_EQ(editDistance("watchdog_timout", "watchdog_timeout"),
            editDistance("watchdog_timeout", "watchdog_timout"));
}

const std::vector<std::string> kFollower = {"band_distance", "band_rows",  "kd",        "kp",
                                            "max_angular",   "max_linear", "min_linear"};

TEST(NearestName, SuggestsTheNameOneTypoAway) {
  EXPECT_EQ(nearestName("max_liner", kFollower), "max_linear");
  EXPECT_EQ(nearestName("band_row", kFollower), "band_rows");
  EXPECT_EQ(nearestName("Kp", kFollower), "kp");  // case counts as a typo
}

TEST(NearestName, PrefersTheNearestAndOnATieTheFirst) {
  EXPECT_EQ(nearestName("min_lnear", kFollower), "min_linear");  // 1 away; max_linear 2
  EXPECT_EQ(nearestName("kx", kFollower), "kd");                 // kd and kp both 1 away
}

TEST(NearestName, SuggestsNothingForAnUnrelatedName) {
  // The tester's names: none is a typo of a parameter the nodes have.
  EXPECT_EQ(nearestName("band_top_fraction", kFollower), std::nullopt);
  EXPECT_EQ(nearestName("max_speed", kFollower), std::nullopt);
  EXPECT_EQ(nearestName("turn_rate", kFollower), std::nullopt);
  EXPECT_EQ(nearestName("x", kFollower), std::nullopt);  // a short name: one edit at most
  EXPECT_EQ(nearestName("anything", {}), std::nullopt);
}

}  // namespace
}  // namespace follow_bot_common
